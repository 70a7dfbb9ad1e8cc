//! Adjoint of `rasterize` (pass 1): a back-to-front replay of each pixel's blended Gaussians that
//! recovers every transmittance by division (T_j = T_{j+1} / (1 - alpha_j), alpha <= 0.99), with
//! the same skip and stop rules as the forward. Gradients reach each Gaussian's colour, depth,
//! mask value, opacity and 2D mean and conic.
use super::Projected;
use super::project_bwd::ProjectedGrads;
use super::rasterize::{PixelState, alpha_at, sign, tile_pixels};
use crate::image::Image;
use crate::pipeline::TileGrid;

/// Upstream gradients of pass 1's layers.
#[derive(Clone, Copy, Debug)]
pub struct RasterizeUpstream<'a> {
    pub transmission: &'a Image<f64>,
    pub depth: &'a Image<f64>,
    pub depth_variance: &'a Image<f64>,
    pub mask: &'a Image<f64>,
    pub alpha: &'a Image<f64>,
}

/// Chain dL/dalpha of Gaussian `i` at one pixel into its opacity, 2D mean and conic.
/// `alpha = min(0.99, o G)`, `G = exp(-(a dx^2 + c dy^2) / 2 - b dx dy)`, `(dx, dy) = pixel - mean`.
#[inline]
pub(crate) fn alpha_bwd(
    p: &Projected,
    pg: &mut ProjectedGrads,
    i: usize,
    g_alpha: f64,
    gauss: f64,
    dx: f64,
    dy: f64,
    unclamped: bool,
) {
    if !unclamped {
        return; // alpha sits at its 0.99 cap: flat in o and G
    }
    let [a, b, c] = p.conic[i];
    pg.opacity[i] += g_alpha * gauss;
    let g_power = g_alpha * p.opacity[i] * gauss;
    pg.mean2d[i].x += g_power * (a * dx + b * dy);
    pg.mean2d[i].y += g_power * (b * dx + c * dy);
    pg.conic[i][0] += g_power * (-0.5 * dx * dx);
    pg.conic[i][1] += g_power * (-dx * dy);
    pg.conic[i][2] += g_power * (-0.5 * dy * dy);
}

pub fn rasterize_bwd(
    p: &Projected,
    values: &[u32],
    ranges: &[(u32, u32)],
    grid: &TileGrid,
    pixels: &[PixelState],
    depth: &Image<f64>,
    background: [f64; 3],
    up: RasterizeUpstream<'_>,
) -> ProjectedGrads {
    let mut pg = ProjectedGrads::zeros(p.len());
    for ty in 0..grid.tiles_y {
        for tx in 0..grid.tiles_x {
            let (start, end) = ranges[(ty * grid.tiles_x + tx) as usize];
            let list = &values[start as usize..end as usize];
            for (x, y) in tile_pixels(grid, tx, ty) {
                let st = pixels[(y * grid.width + x) as usize];
                let (px, py) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
                let gc = [0, 1, 2].map(|c| up.transmission.get(x, y, c));
                let (g_d, g_v, g_m) =
                    (up.depth.get(x, y, 0), up.depth_variance.get(x, y, 0), up.mask.get(x, y, 0));
                let d = depth.get(x, y, 0);
                // V depends on D_t too: dV/dD = -sum w sign(z - D).
                let g_d_total = g_d - g_v * st.depth_sign_sum;
                let (g_zsum, g_wsum) = if st.weight_sum > 0.0 {
                    (g_d_total / st.weight_sum, -g_d_total * d / st.weight_sum)
                } else {
                    (0.0, 0.0)
                };
                // T_final appears in alpha = 1 - T and in the background term of C_t.
                let g_tfinal =
                    -up.alpha.get(x, y, 0) + (0..3).map(|c| gc[c] * background[c]).sum::<f64>();
                let (mut t, mut acc_t) = (st.t_final, g_tfinal * st.t_final);
                let (mut tm, mut acc_m) = (st.tm_final, 0.0);
                for j in (0..st.last_t as usize).rev() {
                    let i = list[j] as usize;
                    let Some((alpha, gauss, dx, dy, unclamped)) = alpha_at(p, i, px, py) else {
                        continue;
                    };
                    let mut g_alpha = 0.0;
                    if !p.glass[i] {
                        let tj = t / (1.0 - alpha);
                        let wgt = alpha * tj;
                        let dz = p.depth[i] - d;
                        let col = p.color[i];
                        let phi = gc[0] * col[0]
                            + gc[1] * col[1]
                            + gc[2] * col[2]
                            + g_zsum * p.depth[i]
                            + g_wsum
                            + g_v * dz.abs();
                        for c in 0..3 {
                            pg.color[i][c] += gc[c] * wgt;
                        }
                        pg.depth[i] += g_zsum * wgt + g_v * wgt * sign(dz);
                        g_alpha += phi * tj - acc_t / (1.0 - alpha);
                        acc_t += phi * wgt;
                        t = tj;
                    }
                    if j < st.last_m as usize {
                        let tmj = tm / (1.0 - alpha);
                        let psi = if p.glass[i] { g_m * p.mask[i] } else { 0.0 };
                        pg.mask[i] += g_m * alpha * tmj * f64::from(u8::from(p.glass[i]));
                        g_alpha += psi * tmj - acc_m / (1.0 - alpha);
                        acc_m += psi * alpha * tmj;
                        tm = tmj;
                    }
                    alpha_bwd(p, &mut pg, i, g_alpha, gauss, dx, dy, unclamped);
                }
            }
        }
    }
    pg
}
