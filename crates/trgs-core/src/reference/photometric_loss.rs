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

/// 3DGS's weight of the D-SSIM term.
pub const DSSIM_LAMBDA: f64 = 0.2;

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
            let (mx, my) = (m_x[i], m_y[i]);
            let a1 = 2.0 * mx * my + SSIM_C1;
            let a2 = 2.0 * (m_xy[i] - mx * my) + SSIM_C2;
            let b1 = mx * mx + my * my + SSIM_C1;
            let b2 = (m_xx[i] - mx * mx) + (m_yy[i] - my * my) + SSIM_C2;
            let s = a1 * a2 / (b1 * b2);
            ssim_sum += s;
            // S = A1 A2 / (B1 B2) with A2, B2 depending on m_x through the (co)variances.
            g_mx[i] = g_s * s * (2.0 * my / a1 - 2.0 * my / a2 - 2.0 * mx / b1 + 2.0 * mx / b2);
            g_mxx[i] = -g_s * s / b2;
            g_mxy[i] = g_s * s * 2.0 / a2;
        }
        let (b_mx, b_mxx, b_mxy) = (blur(&g_mx), blur(&g_mxx), blur(&g_mxy));
        for i in 0..w * h {
            grad.data[i * ch + c] += b_mx[i] + 2.0 * x[i] * b_mxx[i] + y[i] * b_mxy[i];
        }
    }
    let ssim = ssim_sum * inv_n;
    Ok(PhotometricLoss { value: (1.0 - lambda) * l1 + lambda * (1.0 - ssim), l1, ssim, grad })
}

#[cfg(test)]
mod tests {
    use super::*;
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
    fn mismatched_sizes_are_rejected() {
        let a = Image::<f64>::new(4, 4, 3);
        let b = Image::<f64>::new(4, 5, 3);
        assert!(matches!(
            photometric_loss(&a, &b, DSSIM_LAMBDA),
            Err(MetricsError::SizeMismatch { .. })
        ));
    }
}
