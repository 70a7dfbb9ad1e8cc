//! Stage `rasterize` (pass 1): depth-sorted alpha blending of the real camera's view with two
//! transmittances. Primary Gaussians advance T_t (transmission colour C_t, depth D_t, alpha) and
//! T_m (the glass mask M, which they occlude but never paint); glass Gaussians advance only T_m.
//! A Gaussian that would bring T_t below 1e-4 stops the pixel; one that would bring T_m below it
//! stops M only. A second walk over the blended Gaussians gives the depth variance
//! V = sum_i w_i |z_i - D_t|, which needs D_t first. (The GPU's walk sums the near side only
//! and doubles it, the same number since D_t is the weighted mean; this twin keeps the
//! definition.)
use super::Projected;
use crate::image::Image;
use crate::pipeline::{MAX_ALPHA, MIN_ALPHA, MIN_TRANSMITTANCE, TILE_SIZE, TileGrid};

/// What the backward replay needs of one pixel of pass 1.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelState {
    /// Final transmittance of the primary chain.
    pub t_final: f64,
    /// Final transmittance of the mask chain.
    pub tm_final: f64,
    /// Entries `[0, last_t)` of the tile's list were considered by the primary chain.
    pub last_t: u32,
    /// Entries `[0, last_m)` were considered by the mask chain (`last_m <= last_t`).
    pub last_m: u32,
    /// sum_i w_i over the primary chain (w_i = alpha_i T_i).
    pub weight_sum: f64,
    /// sum_i w_i sign(z_i - D_t), the derivative of V with respect to -D_t.
    pub depth_sign_sum: f64,
}

/// Pass 1 layers of one view.
#[derive(Clone, Debug)]
pub struct RasterizeOutput {
    /// C_t, RGB, with `background` behind the last transmittance.
    pub transmission: Image<f64>,
    /// D_t = sum z w / sum w (zero where nothing was blended).
    pub depth: Image<f64>,
    /// V = sum w |z - D_t|.
    pub depth_variance: Image<f64>,
    /// M = sum over glass Gaussians of m alpha T_m.
    pub mask: Image<f64>,
    /// 1 - T_t.
    pub alpha: Image<f64>,
    pub pixels: Vec<PixelState>,
}

/// A Gaussian's alpha at a pixel centre, as `(alpha, G, dx, dy, unclamped)` with
/// `(dx, dy) = pixel - mean`, or None when it is skipped (alpha < 1/255 or a non-decaying
/// exponent from a numerically bad conic).
#[inline]
pub(crate) fn alpha_at(
    p: &Projected,
    i: usize,
    px: f64,
    py: f64,
) -> Option<(f64, f64, f64, f64, bool)> {
    let [a, b, c] = p.conic[i];
    let (dx, dy) = (px - p.mean2d[i].x, py - p.mean2d[i].y);
    let power = -0.5 * (a * dx * dx + c * dy * dy) - b * dx * dy;
    if !(power <= 0.0) {
        return None;
    }
    let g = power.exp();
    let raw = p.opacity[i] * g;
    let alpha = raw.min(MAX_ALPHA);
    if !(alpha >= MIN_ALPHA) {
        return None;
    }
    Some((alpha, g, dx, dy, raw < MAX_ALPHA))
}

/// Iterate the pixels of tile `(tx, ty)` inside the image.
pub(crate) fn tile_pixels(grid: &TileGrid, tx: u32, ty: u32) -> impl Iterator<Item = (u32, u32)> {
    let (x0, y0) = (tx * TILE_SIZE, ty * TILE_SIZE);
    let (x1, y1) = ((x0 + TILE_SIZE).min(grid.width), (y0 + TILE_SIZE).min(grid.height));
    (y0..y1).flat_map(move |y| (x0..x1).map(move |x| (x, y)))
}

/// Rasterise pass 1 from the sorted per-tile lists (`values` indexed by `ranges`).
pub fn rasterize(
    p: &Projected,
    values: &[u32],
    ranges: &[(u32, u32)],
    grid: &TileGrid,
    background: [f64; 3],
) -> RasterizeOutput {
    let (w, h) = (grid.width, grid.height);
    let mut out = RasterizeOutput {
        transmission: Image::new(w, h, 3),
        depth: Image::new(w, h, 1),
        depth_variance: Image::new(w, h, 1),
        mask: Image::new(w, h, 1),
        alpha: Image::new(w, h, 1),
        pixels: vec![PixelState::default(); (w * h) as usize],
    };
    for ty in 0..grid.tiles_y {
        for tx in 0..grid.tiles_x {
            let (start, end) = ranges[(ty * grid.tiles_x + tx) as usize];
            let list = &values[start as usize..end as usize];
            for (x, y) in tile_pixels(grid, tx, ty) {
                shade_pixel(p, list, x, y, background, &mut out);
            }
        }
    }
    out
}

fn shade_pixel(
    p: &Projected,
    list: &[u32],
    x: u32,
    y: u32,
    background: [f64; 3],
    out: &mut RasterizeOutput,
) {
    let (px, py) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
    let (mut t, mut tm) = (1.0f64, 1.0f64);
    let mut m_active = true;
    let (mut color, mut wsum, mut zsum, mut mask) = ([0.0f64; 3], 0.0, 0.0, 0.0);
    let n = list.len() as u32;
    let (mut last_t, mut last_m) = (n, n);
    for (j, &gi) in list.iter().enumerate() {
        let i = gi as usize;
        let Some((alpha, ..)) = alpha_at(p, i, px, py) else { continue };
        if !p.glass[i] {
            let next_t = t * (1.0 - alpha);
            if next_t < MIN_TRANSMITTANCE {
                last_t = j as u32;
                if m_active {
                    last_m = j as u32;
                }
                break;
            }
            let wgt = alpha * t;
            for c in 0..3 {
                color[c] += p.color[i][c] * wgt;
            }
            wsum += wgt;
            zsum += p.depth[i] * wgt;
            t = next_t;
        }
        if m_active {
            let next_m = tm * (1.0 - alpha);
            if next_m < MIN_TRANSMITTANCE {
                m_active = false;
                last_m = j as u32;
            } else {
                mask += p.mask[i] * alpha * tm;
                tm = next_m;
            }
        }
    }
    let depth = if wsum > 0.0 { zsum / wsum } else { 0.0 };
    // Second walk: the spread of the blended depths around D_t.
    let (mut variance, mut sign_sum, mut tv) = (0.0, 0.0, 1.0f64);
    for &gi in &list[..last_t as usize] {
        let i = gi as usize;
        if p.glass[i] {
            continue;
        }
        let Some((alpha, ..)) = alpha_at(p, i, px, py) else { continue };
        let wgt = alpha * tv;
        let dz = p.depth[i] - depth;
        variance += wgt * dz.abs();
        sign_sum += wgt * sign(dz);
        tv *= 1.0 - alpha;
    }
    for c in 0..3 {
        out.transmission.set(x, y, c as u32, color[c] + t * background[c]);
    }
    out.depth.set(x, y, 0, depth);
    out.depth_variance.set(x, y, 0, variance);
    out.mask.set(x, y, 0, mask);
    out.alpha.set(x, y, 0, 1.0 - t);
    out.pixels[(y * out.depth.width + x) as usize] = PixelState {
        t_final: t,
        tm_final: tm,
        last_t,
        last_m,
        weight_sum: wsum,
        depth_sign_sum: sign_sum,
    };
}

/// sign with sign(0) = 0, the subgradient |x|' the backward uses.
#[inline]
pub(crate) fn sign(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}
