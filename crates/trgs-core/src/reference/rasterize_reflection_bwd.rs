//! Adjoint of `rasterize_reflection` (pass 2): the back-to-front replay over the footprint's
//! tiles, into each mirrored Gaussian's colour, reflection intensity, opacity, 2D mean and conic.
use super::Projected;
use super::project_bwd::ProjectedGrads;
use super::rasterize::{alpha_at, tile_pixels};
use super::rasterize_bwd::alpha_bwd;
use super::rasterize_reflection::ReflectionPixelState;
use crate::image::Image;
use crate::pipeline::{TileGrid, TileRect};

pub fn rasterize_reflection_bwd(
    p: &Projected,
    values: &[u32],
    ranges: &[(u32, u32)],
    grid: &TileGrid,
    footprint: &TileRect,
    pixels: &[ReflectionPixelState],
    g_raw_color: &Image<f64>,
    g_intensity: &Image<f64>,
) -> ProjectedGrads {
    let mut pg = ProjectedGrads::zeros(p.len());
    for ty in footprint.y0..footprint.y1 {
        for tx in footprint.x0..footprint.x1 {
            let (start, end) = ranges[(ty * grid.tiles_x + tx) as usize];
            let list = &values[start as usize..end as usize];
            for (x, y) in tile_pixels(grid, tx, ty) {
                let st = pixels[(y * grid.width + x) as usize];
                let (px, py) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
                let gc = [0, 1, 2].map(|c| g_raw_color.get(x, y, c));
                let ga = g_intensity.get(x, y, 0);
                let (mut t, mut acc) = (st.t_final, 0.0);
                for j in (0..st.last as usize).rev() {
                    let i = list[j] as usize;
                    let Some((alpha, gauss, dx, dy, unclamped)) = alpha_at(p, i, px, py) else {
                        continue;
                    };
                    let tj = t / (1.0 - alpha);
                    let wgt = alpha * tj;
                    let col = p.color[i];
                    let phi =
                        gc[0] * col[0] + gc[1] * col[1] + gc[2] * col[2] + ga * p.reflection[i];
                    for c in 0..3 {
                        pg.color[i][c] += gc[c] * wgt;
                    }
                    pg.reflection[i] += ga * wgt;
                    let g_alpha = phi * tj - acc / (1.0 - alpha);
                    acc += phi * wgt;
                    t = tj;
                    alpha_bwd(p, &mut pg, i, g_alpha, gauss, dx, dy, unclamped);
                }
            }
        }
    }
    pg
}
