//! Stage `exposure` and its adjoint `exposure_bwd` (the CPU twins of
//! shaders/training/exposure.wgsl and exposure_bwd.wgsl): a training view's exposure and white
//! balance as an affine map of the rendered colour, `C' = A C + b` with a 3x3 `A` and an offset
//! `b` per view, which the photometric loss sees in place of `C` (the INRIA code's exposure
//! compensation). A photo taken darker, warmer or with another gain is then explained by its own
//! twelve numbers rather than by view-dependent colour or floaters in the shared model.
//!
//! The adjoint takes dL/dC' and gives dL/dC = A^T dL/dC' per pixel and dL/d(A, b) summed over
//! the pixels: `dL/dA_ij = sum_p g'_i C_j`, `dL/db_i = sum_p g'_i`.
use crate::image::Image;
use crate::pipeline::ExposureMatrix;

/// `render` (RGB, or RGB plus channels passed through unchanged) mapped by `m`.
pub fn exposure(render: &Image<f64>, m: &ExposureMatrix) -> Image<f64> {
    let mut out = render.clone();
    let ch = render.channels as usize;
    for (o, c) in out.data.chunks_mut(ch).zip(render.data.chunks(ch)) {
        o[..3].copy_from_slice(&exposure_pixel(m, [c[0], c[1], c[2]]));
    }
    out
}

/// `m` applied to one colour.
pub fn exposure_pixel(m: &ExposureMatrix, c: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| m[i][0] * c[0] + m[i][1] * c[1] + m[i][2] * c[2] + m[i][3])
}

/// dL/d(the rendered colour) and dL/d(the matrix) of [`exposure`].
#[derive(Clone, Debug, PartialEq)]
pub struct ExposureGrads {
    /// dL/dC, the layout of the render (channels past RGB pass their gradient through).
    pub color: Image<f64>,
    /// dL/dm, row by row: `[A_i0, A_i1, A_i2, b_i]`.
    pub matrix: ExposureMatrix,
}

/// The adjoint of [`exposure`] at `render` for the upstream gradient `grad` (dL/dC', the
/// render's layout).
pub fn exposure_bwd(render: &Image<f64>, m: &ExposureMatrix, grad: &Image<f64>) -> ExposureGrads {
    let mut color = grad.clone();
    let mut matrix = [[0.0; 4]; 3];
    let ch = render.channels as usize;
    for ((gc, c), g) in
        color.data.chunks_mut(ch).zip(render.data.chunks(ch)).zip(grad.data.chunks(ch))
    {
        for j in 0..3 {
            gc[j] = (0..3).map(|i| m[i][j] * g[i]).sum();
        }
        for i in 0..3 {
            for j in 0..3 {
                matrix[i][j] += g[i] * c[j];
            }
            matrix[i][3] += g[i];
        }
    }
    ExposureGrads { color, matrix }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn random_image(w: u32, h: u32, ch: u32, rng: &mut Rng) -> Image<f64> {
        let mut im = Image::new(w, h, ch);
        im.data.iter_mut().for_each(|v| *v = rng.range(-0.2, 1.2));
        im
    }

    /// A loss of the exposed image with random weights: sum w * C'.
    fn loss(render: &Image<f64>, m: &ExposureMatrix, w: &Image<f64>) -> f64 {
        exposure(render, m).data.iter().zip(&w.data).map(|(a, b)| a * b).sum()
    }

    #[test]
    fn the_adjoint_matches_central_differences_for_every_input() {
        let mut rng = Rng::new(11);
        for ch in [3, 4] {
            let render = random_image(5, 4, ch, &mut rng);
            let w = random_image(5, 4, ch, &mut rng);
            let m: ExposureMatrix =
                std::array::from_fn(|_| std::array::from_fn(|_| rng.range(-0.5, 1.5)));
            let g = exposure_bwd(&render, &m, &w);
            let h = 1e-6;
            for i in 0..3 {
                for j in 0..4 {
                    let (mut up, mut down) = (m, m);
                    up[i][j] += h;
                    down[i][j] -= h;
                    let fd = (loss(&render, &up, &w) - loss(&render, &down, &w)) / (2.0 * h);
                    assert!((fd - g.matrix[i][j]).abs() < 1e-7 * (1.0 + fd.abs()), "m{i}{j}");
                }
            }
            for k in 0..render.data.len() {
                let (mut up, mut down) = (render.clone(), render.clone());
                up.data[k] += h;
                down.data[k] -= h;
                let fd = (loss(&up, &m, &w) - loss(&down, &m, &w)) / (2.0 * h);
                assert!((fd - g.color.data[k]).abs() < 1e-7 * (1.0 + fd.abs()), "sample {k}");
            }
        }
    }

    #[test]
    fn the_identity_changes_nothing_and_extreme_values_stay_finite() {
        let mut rng = Rng::new(2);
        let render = random_image(3, 3, 4, &mut rng);
        assert_eq!(exposure(&render, &crate::pipeline::EXPOSURE_IDENTITY), render);
        let big = Image::filled(2, 2, 3, 1e30);
        let m = [[1e8, 0.0, 0.0, 0.0], [0.0, 1e-8, 0.0, 0.0], [0.0, 0.0, 1.0, -1e8]];
        assert!(exposure(&big, &m).data.iter().all(|v| v.is_finite()));
        let g = exposure_bwd(&big, &m, &Image::filled(2, 2, 3, 1.0));
        assert!(g.matrix.iter().flatten().all(|v| v.is_finite()));
    }
}
