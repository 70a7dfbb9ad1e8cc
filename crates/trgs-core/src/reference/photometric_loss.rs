//! Stage `photometric_loss` (the CPU twin of training's image loss): 3DGS's
//! `(1 - lambda) L1 + lambda (1 - SSIM)` between a rendered image and its target, and its gradient
//! with respect to every rendered sample.
//!
//! SSIM is [`crate::metrics::ssim_map`]'s with zero padding (3DGS's `conv2d`), averaged over every
//! pixel and channel. Its gradient goes through the five windowed moments
//! `m_x = G*x, m_y = G*y, m_xx = G*x^2, m_yy = G*y^2, m_xy = G*xy`: with `g_m = dL/dS dS/dm` at
//! each pixel, `dL/dx = G*g_mx + 2 x (G*g_mxx) + y (G*g_mxy)`, because the zero-padded correlation
//! with a symmetric window is its own adjoint.
use crate::image::Image;
use crate::metrics::{Border, MetricsError, SSIM_C1, SSIM_C2, gaussian_filter};

/// The loss of one image and dL/d(rendered image).
#[derive(Clone, Debug)]
pub struct PhotometricLoss {
    /// `(1 - lambda) l1 + lambda (1 - ssim)`.
    pub value: f64,
    /// Mean absolute error over all samples.
    pub l1: f64,
    /// Mean SSIM over all samples (zero padding).
    pub ssim: f64,
    /// dL/d(each sample of the rendered image), same layout.
    pub grad: Image<f64>,
}

/// The loss of `render` against `target` (same size, any channel count) and its gradient.
pub fn photometric_loss(
    render: &Image<f64>,
    target: &Image<f64>,
    lambda: f64,
) -> Result<PhotometricLoss, MetricsError> {
    photometric_loss_covered(render, target, None, lambda)
}

/// [`photometric_loss`] where only the pixels `covered` marks (nonzero; one channel, the image's
/// size) count: the loss sees both images multiplied by the coverage, so a pixel without a source
/// (the border of an undistorted photo) adds no error, no SSIM window reads a colour there, and
/// its gradient is zero. The means stay over every sample.
pub fn photometric_loss_covered(
    render: &Image<f64>,
    target: &Image<f64>,
    covered: Option<&Image<u8>>,
    lambda: f64,
) -> Result<PhotometricLoss, MetricsError> {
    let Some(covered) = covered else { return uncovered_loss(render, target, lambda) };
    if (covered.width, covered.height, covered.channels) != (render.width, render.height, 1) {
        return Err(MetricsError::SizeMismatch {
            a: (render.width, render.height, 1),
            b: (covered.width, covered.height, covered.channels),
        });
    }
    let mask = |im: &Image<f64>| im.clone().zero_uncovered(covered);
    let mut loss = uncovered_loss(&mask(render), &mask(target), lambda)?;
    loss.grad = loss.grad.zero_uncovered(covered);
    Ok(loss)
}

/// The loss over every pixel.
fn uncovered_loss(
    render: &Image<f64>,
    target: &Image<f64>,
    lambda: f64,
) -> Result<PhotometricLoss, MetricsError> {
    let (w, h, ch) = (render.width as usize, render.height as usize, render.channels as usize);
    if (render.width, render.height, render.channels)
        != (target.width, target.height, target.channels)
    {
        return Err(MetricsError::SizeMismatch {
            a: (render.width, render.height, render.channels),
            b: (target.width, target.height, target.channels),
        });
    }
    let n = w * h * ch;
    if n == 0 {
        return Err(MetricsError::Empty {
            width: render.width,
            height: render.height,
            channels: render.channels,
        });
    }
    for im in [render, target] {
        if im.data.len() != n {
            return Err(MetricsError::Malformed {
                width: im.width,
                height: im.height,
                channels: im.channels,
                len: im.data.len(),
                expected: n,
            });
        }
    }
    let inv_n = 1.0 / n as f64;
    let mut grad = Image::<f64>::new(render.width, render.height, render.channels);
    let mut l1 = 0.0;
    for ((g, &x), &y) in grad.data.iter_mut().zip(&render.data).zip(&target.data) {
        l1 += (x - y).abs();
        let sign = if x > y {
            1.0
        } else if x < y {
            -1.0
        } else {
            0.0
        };
        *g = (1.0 - lambda) * sign * inv_n;
    }
    l1 *= inv_n;

    let blur = |p: &[f64]| gaussian_filter(p, w, h, Border::Zero);
    let mut ssim_sum = 0.0;
    // dL/dS at every sample of the SSIM map.
    let g_s = -lambda * inv_n;
    for c in 0..ch {
        let x: Vec<f64> = (0..w * h).map(|i| render.data[i * ch + c]).collect();
        let y: Vec<f64> = (0..w * h).map(|i| target.data[i * ch + c]).collect();
        let product =
            |p: &[f64], q: &[f64]| -> Vec<f64> { p.iter().zip(q).map(|(u, v)| u * v).collect() };
        let m_x = blur(&x);
        let m_y = blur(&y);
        let m_xx = blur(&product(&x, &x));
        let m_yy = blur(&product(&y, &y));
        let m_xy = blur(&product(&x, &y));
        let mut g_mx = vec![0.0; w * h];
        let mut g_mxx = vec![0.0; w * h];
        let mut g_mxy = vec![0.0; w * h];
        for i in 0..w * h {
            let t = ssim_terms(m_x[i], m_y[i], m_xx[i], m_yy[i], m_xy[i]);
            ssim_sum += t.s;
            (g_mx[i], g_mxx[i], g_mxy[i]) = (g_s * t.d_mx, g_s * t.d_mxx, g_s * t.d_mxy);
        }
        let (b_mx, b_mxx, b_mxy) = (blur(&g_mx), blur(&g_mxx), blur(&g_mxy));
        for i in 0..w * h {
            grad.data[i * ch + c] += b_mx[i] + 2.0 * x[i] * b_mxx[i] + y[i] * b_mxy[i];
        }
    }
    let ssim = ssim_sum * inv_n;
    Ok(PhotometricLoss { value: (1.0 - lambda) * l1 + lambda * (1.0 - ssim), l1, ssim, grad })
}

/// SSIM at one sample from its window means, and its derivatives by m_x, m_xx and m_xy.
struct SsimTerms {
    s: f64,
    d_mx: f64,
    d_mxx: f64,
    d_mxy: f64,
}

fn ssim_terms(mx: f64, my: f64, mxx: f64, myy: f64, mxy: f64) -> SsimTerms {
    let a1 = 2.0 * mx * my + SSIM_C1;
    let a2 = 2.0 * (mxy - mx * my) + SSIM_C2;
    let b1 = mx * mx + my * my + SSIM_C1;
    let b2 = (mxx - mx * mx) + (myy - my * my) + SSIM_C2;
    let s = a1 * a2 / (b1 * b2);
    // S = A1 A2 / (B1 B2) with A2, B2 depending on m_x through the (co)variances. S/A1 and S/A2
    // are written A2/(B1 B2) and A1/(B1 B2): A2 (twice the covariance plus C2) can be exactly
    // zero, where S (A2/A2) would be 0 inf = NaN. B1 >= C1 > 0 and B2 >= C2 > 0.
    let inv_b = 1.0 / (b1 * b2);
    SsimTerms {
        s,
        d_mx: 2.0 * my * (a2 - a1) * inv_b - 2.0 * mx * s / b1 + 2.0 * mx * s / b2,
        d_mxx: -s / b2,
        d_mxy: 2.0 * a1 * inv_b,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::DSSIM_LAMBDA;
    use crate::rng::Rng;

    fn random_image(w: u32, h: u32, rng: &mut Rng) -> Image<f64> {
        let mut im = Image::<f64>::new(w, h, 3);
        for v in &mut im.data {
            *v = rng.uniform();
        }
        im
    }

    #[test]
    fn ssim_matches_the_metric_and_identical_images_cost_nothing() {
        let mut rng = Rng::new(3);
        let a = random_image(17, 13, &mut rng);
        let b = random_image(17, 13, &mut rng);
        let loss = photometric_loss(&a, &b, DSSIM_LAMBDA).expect("valid images");
        let to32 = |im: &Image<f64>| Image::<f32> {
            width: im.width,
            height: im.height,
            channels: im.channels,
            data: im.data.iter().map(|&v| v as f32).collect(),
        };
        let map =
            crate::metrics::ssim_map(&to32(&a), &to32(&b), Border::Zero).expect("valid images");
        let mean = map.data.iter().sum::<f64>() / map.data.len() as f64;
        assert!((loss.ssim - mean).abs() < 1e-6, "{} vs {mean}", loss.ssim);
        let same = photometric_loss(&a, &a, DSSIM_LAMBDA).expect("valid images");
        assert!(same.value.abs() < 1e-12 && same.l1 == 0.0, "{}", same.value);
    }

    #[test]
    fn gradient_matches_central_differences() {
        let mut rng = Rng::new(11);
        let (w, h) = (15, 12);
        let a = random_image(w, h, &mut rng);
        let b = random_image(w, h, &mut rng);
        let loss = photometric_loss(&a, &b, DSSIM_LAMBDA).expect("valid images");
        let eps = 1e-6;
        let mut worst = 0.0f64;
        for k in (0..a.data.len()).step_by(7) {
            let mut p = a.clone();
            p.data[k] += eps;
            let mut m = a.clone();
            m.data[k] -= eps;
            let fd = (photometric_loss(&p, &b, DSSIM_LAMBDA).expect("valid images").value
                - photometric_loss(&m, &b, DSSIM_LAMBDA).expect("valid images").value)
                / (2.0 * eps);
            let scale = fd.abs().max(loss.grad.data[k].abs()).max(1e-9);
            worst = worst.max((fd - loss.grad.data[k]).abs() / scale);
        }
        assert!(worst < 1e-5, "worst relative error {worst:e}");
    }

    #[test]
    fn uncovered_pixels_neither_count_nor_train() {
        let mut rng = Rng::new(5);
        let (w, h) = (14, 11);
        let a = random_image(w, h, &mut rng);
        let b = random_image(w, h, &mut rng);
        // A ragged border without a source, as an undistorted photo's.
        let mut covered = Image::<u8>::new(w, h, 1);
        for y in 0..h {
            for x in 0..w {
                covered.set(x, y, 0, u8::from(x > y % 3 && y + 1 < h));
            }
        }
        let loss = photometric_loss_covered(&a, &b, Some(&covered), DSSIM_LAMBDA).expect("valid");
        // Whatever the render shows where the photo has no source changes nothing.
        let mut other = a.clone();
        for (i, v) in other.data.iter_mut().enumerate() {
            if covered.data[i / 3] == 0 {
                *v = rng.uniform();
                assert_eq!(loss.grad.data[i], 0.0, "sample {i} has no source");
            }
        }
        let same = photometric_loss_covered(&other, &b, Some(&covered), DSSIM_LAMBDA).expect("ok");
        assert!((same.value - loss.value).abs() < 1e-15);
        // The gradient at the covered samples is the loss's (central differences).
        let eps = 1e-6;
        for k in (0..a.data.len()).step_by(5).filter(|k| covered.data[k / 3] != 0) {
            let at = |d: f64| {
                let mut p = a.clone();
                p.data[k] += d;
                photometric_loss_covered(&p, &b, Some(&covered), DSSIM_LAMBDA).expect("ok").value
            };
            let fd = (at(eps) - at(-eps)) / (2.0 * eps);
            let scale = fd.abs().max(loss.grad.data[k].abs()).max(1e-9);
            assert!((fd - loss.grad.data[k]).abs() / scale < 1e-5, "sample {k}");
        }
        let wrong = Image::<u8>::new(w + 1, h, 1);
        assert!(photometric_loss_covered(&a, &b, Some(&wrong), DSSIM_LAMBDA).is_err());
    }

    #[test]
    fn ssim_derivatives_are_finite_where_the_covariance_term_is_zero() {
        // Dark windows (small means) make the zero reachable in floating point.
        let (mx, my, mxx, myy) = (0.03, 0.03, 0.002, 0.002);
        // A2 = 2 (m_xy - m_x m_y) + C2 = 0 exactly: the m_xy next to the exact root where the
        // f64 arithmetic gives zero.
        let a2 = |mxy: f64| 2.0 * (mxy - mx * my) + SSIM_C2;
        let root = mx * my - SSIM_C2 / 2.0;
        let mxy = (-64i64..=64)
            .map(|k| f64::from_bits((root.to_bits() as i64 + k) as u64))
            .find(|&v| a2(v) == 0.0)
            .expect("an m_xy with A2 = 0 within 64 ulps");
        let t = ssim_terms(mx, my, mxx, myy, mxy);
        assert_eq!(t.s, 0.0);
        assert!([t.d_mx, t.d_mxx, t.d_mxy].iter().all(|v| v.is_finite()), "{:?}", t.d_mx);
        // And they are the derivatives: central differences at that point.
        let e = 1e-6;
        let fd = |f: &dyn Fn(f64) -> f64| (f(e) - f(-e)) / (2.0 * e);
        let by_mx = fd(&|d| ssim_terms(mx + d, my, mxx, myy, mxy).s);
        let by_mxx = fd(&|d| ssim_terms(mx, my, mxx + d, myy, mxy).s);
        let by_mxy = fd(&|d| ssim_terms(mx, my, mxx, myy, mxy + d).s);
        for (a, b) in [(t.d_mx, by_mx), (t.d_mxx, by_mxx), (t.d_mxy, by_mxy)] {
            assert!((a - b).abs() < 1e-6 * (1.0 + b.abs()), "{a} against {b}");
        }
    }

    #[test]
    fn mismatched_sizes_are_rejected() {
        let a = Image::<f64>::new(4, 4, 3);
        let b = Image::<f64>::new(4, 5, 3);
        assert!(matches!(
            photometric_loss(&a, &b, DSSIM_LAMBDA),
            Err(MetricsError::SizeMismatch { .. })
        ));
    }
}
