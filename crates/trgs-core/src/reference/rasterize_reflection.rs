//! Stage `rasterize_reflection` (pass 2): blending of one mirrored view, restricted to the tiles
//! of the plane's footprint and, within them, to the pixels whose camera ray hits the plane's
//! rectangle from the front (no other pixel can show this reflection). It produces the raw
//! reflection colour C_raw = sum c_i w_i and the intensity A = sum a_i w_i with a single
//! transmittance; both are zero, and the pixel state default, everywhere else.
use super::Projected;
use super::rasterize::{alpha_at, tile_pixels};
use crate::image::Image;
use crate::pipeline::{MIN_TRANSMITTANCE, TileGrid, TileRect};
use crate::plane_math::ray_rectangle_hit;
use crate::scene::{Camera, ReflectionPlane};

/// What the backward replay needs of one pixel of pass 2.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ReflectionPixelState {
    pub t_final: f64,
    /// Entries `[0, last)` of the tile's list were considered.
    pub last: u32,
}

#[derive(Clone, Debug)]
pub struct ReflectionOutput {
    /// C_raw, RGB.
    pub raw_color: Image<f64>,
    /// A.
    pub intensity: Image<f64>,
    pub pixels: Vec<ReflectionPixelState>,
}

pub fn rasterize_reflection(
    p: &Projected,
    values: &[u32],
    ranges: &[(u32, u32)],
    grid: &TileGrid,
    footprint: &TileRect,
    camera: &Camera,
    plane: &ReflectionPlane,
) -> ReflectionOutput {
    let origin = camera.pose.centre();
    let (w, h) = (grid.width, grid.height);
    let mut out = ReflectionOutput {
        raw_color: Image::new(w, h, 3),
        intensity: Image::new(w, h, 1),
        pixels: vec![ReflectionPixelState::default(); (w * h) as usize],
    };
    for ty in footprint.y0..footprint.y1 {
        for tx in footprint.x0..footprint.x1 {
            let (start, end) = ranges[(ty * grid.tiles_x + tx) as usize];
            let list = &values[start as usize..end as usize];
            for (x, y) in tile_pixels(grid, tx, ty) {
                if ray_rectangle_hit(plane, origin, camera.pixel_ray(x, y)).is_none() {
                    continue;
                }
                let (px, py) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
                let mut t = 1.0f64;
                let (mut color, mut intensity) = ([0.0f64; 3], 0.0);
                let mut last = list.len() as u32;
                for (j, &gi) in list.iter().enumerate() {
                    let i = gi as usize;
                    let Some((alpha, ..)) = alpha_at(p, i, px, py) else { continue };
                    let next_t = t * (1.0 - alpha);
                    if next_t < MIN_TRANSMITTANCE {
                        last = j as u32;
                        break;
                    }
                    let wgt = alpha * t;
                    for c in 0..3 {
                        color[c] += p.color[i][c] * wgt;
                    }
                    intensity += p.reflection[i] * wgt;
                    t = next_t;
                }
                for c in 0..3 {
                    out.raw_color.set(x, y, c as u32, color[c]);
                }
                out.intensity.set(x, y, 0, intensity);
                out.pixels[(y * w + x) as usize] = ReflectionPixelState { t_final: t, last };
            }
        }
    }
    out
}
