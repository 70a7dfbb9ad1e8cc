//! A view's exposure fitted in closed form: the affine colour map `C' = A C + b` (stage
//! `exposure`'s [`ExposureMatrix`]) that takes a render closest to its photo in the least-squares
//! sense over the pixels a caller selects. Evaluation uses it for the test views, whose exposure
//! training never saw: fitted on the left half of a test photo and scored on the right half (the
//! INRIA code's `train_test_exp` protocol), so that a model trained with per-view exposures is
//! compared fairly with one trained without.
//!
//! Each output channel is its own 4-parameter regression on `(C, 1)`, with a ridge term pulling
//! toward the identity, `lambda = RIDGE * n`: a flat or grey region (singular normal equations)
//! then gives the identity's columns rather than an unbounded matrix.
use crate::image::Image;
use crate::pipeline::{EXPOSURE_IDENTITY, ExposureMatrix};
use glam::{DMat4, DVec4};

/// The ridge weight per pixel. Small enough that a region of a few thousand pixels with any
/// colour variation is fitted as it is, large enough to keep a degenerate one finite.
const RIDGE: f64 = 1e-4;

/// The exposure that maps `render` closest to `photo` over the pixels where `select(x, y)` holds
/// (both images RGB or more, same size; only RGB is read). No pixel selected: the identity.
pub fn fit_exposure(
    render: &Image<f32>,
    photo: &Image<f32>,
    select: impl Fn(u32, u32) -> bool,
) -> ExposureMatrix {
    let mut xtx = [[0.0f64; 4]; 4];
    let mut xty = [[0.0f64; 4]; 3];
    let mut n = 0usize;
    for y in 0..render.height.min(photo.height) {
        for x in 0..render.width.min(photo.width) {
            if !select(x, y) {
                continue;
            }
            let c = [0, 1, 2].map(|k| f64::from(render.get(x, y, k)));
            let row = [c[0], c[1], c[2], 1.0];
            for i in 0..4 {
                for j in 0..4 {
                    xtx[i][j] += row[i] * row[j];
                }
            }
            for (k, t) in xty.iter_mut().enumerate() {
                let target = f64::from(photo.get(x, y, k as u32));
                for i in 0..4 {
                    t[i] += row[i] * target;
                }
            }
            n += 1;
        }
    }
    if n == 0 {
        return EXPOSURE_IDENTITY;
    }
    let lambda = RIDGE * n as f64;
    for (i, r) in xtx.iter_mut().enumerate() {
        r[i] += lambda;
    }
    let inverse = DMat4::from_cols_array_2d(&xtx).inverse();
    std::array::from_fn(|k| {
        let prior = DVec4::from_array(EXPOSURE_IDENTITY[k]);
        let solved = inverse * (DVec4::from_array(xty[k]) + lambda * prior);
        if solved.is_finite() { solved.to_array() } else { EXPOSURE_IDENTITY[k] }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::exposure;

    fn ramp(w: u32, h: u32) -> Image<f32> {
        let mut im = Image::new(w, h, 3);
        for y in 0..h {
            for x in 0..w {
                let v = [
                    x as f32 / w as f32,
                    y as f32 / h as f32,
                    ((x * 7 + y * 3) % 11) as f32 / 11.0,
                ];
                for k in 0..3 {
                    im.set(x, y, k, v[k as usize]);
                }
            }
        }
        im
    }

    #[test]
    fn a_known_exposure_is_recovered_from_half_the_image() {
        let render = ramp(40, 30);
        let truth: ExposureMatrix =
            [[0.8, 0.05, 0.0, 0.02], [0.0, 0.9, 0.1, -0.01], [0.03, 0.0, 1.1, 0.05]];
        let photo = exposure(&render.map(f64::from), &truth).map(|v| v as f32);
        let fitted = fit_exposure(&render, &photo, |x, _| x < 20);
        for (f, t) in fitted.iter().flatten().zip(truth.iter().flatten()) {
            // The ridge pulls toward the identity by about RIDGE relative to the data.
            assert!((f - t).abs() < 2e-3, "{fitted:?} against {truth:?}");
        }
    }

    #[test]
    fn a_flat_render_gives_a_finite_exposure_near_the_identity_gain() {
        let render = Image::filled(16, 16, 3, 0.5f32);
        let photo = Image::filled(16, 16, 3, 0.25f32);
        let fitted = fit_exposure(&render, &photo, |_, _| true);
        assert!(fitted.iter().flatten().all(|v| v.is_finite()));
        // Every colour the fit saw maps onto the photo's.
        let mapped = crate::reference::exposure_pixel(&fitted, [0.5; 3]);
        assert!(mapped.iter().all(|v| (v - 0.25).abs() < 1e-3), "{mapped:?}");
    }

    #[test]
    fn no_selected_pixel_gives_the_identity() {
        let render = ramp(8, 8);
        assert_eq!(fit_exposure(&render, &render, |_, _| false), EXPOSURE_IDENTITY);
    }
}
