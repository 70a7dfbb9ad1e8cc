//! Image metrics as 3DGS evaluates them: PSNR and SSIM on [0, 1] images, computed in f64.
//!
//! Two SSIM conventions are provided because the numbers differ measurably near the borders:
//!
//! - [`ssim`] is 3DGS's `utils/loss_utils.py::ssim`, used both by training (the D-SSIM term) and by
//!   its `metrics.py`: an 11x11 Gaussian window (sigma 1.5, normalised), `conv2d` with zero
//!   padding of 5, and the mean of the full-size SSIM map over all pixels and channels;
//! - [`ssim_skimage`] is scikit-image's `structural_similarity(gaussian_weights=True, sigma=1.5,
//!   use_sample_covariance=False, data_range=1)`: the same window (truncate 3.5 gives radius
//!   `int(3.5 * 1.5 + 0.5) = 5`), but filtered with `scipy.ndimage`'s `reflect` border (half-sample
//!   symmetric, `d c b a | a b c d | d c b a`) and averaged only after cropping 5 pixels from
//!   every border; with `channel_axis` it is the mean of the per-channel values.
//!
//! The windowed sums are separable: [`gaussian_filter`] runs the 1D window along rows, then along
//! columns, which is exactly the 2D correlation with the outer-product window for either border
//! (zero padding of a separable kernel, and reflection, both act per axis). The GPU D-SSIM loss
//! can use [`ssim_map`] with [`Border::Zero`] as its CPU twin.
use crate::image::Image;

/// Side of the SSIM window.
pub const SSIM_WINDOW: usize = 11;
/// Half the window side: the padding of 3DGS's conv2d and the border scikit-image crops.
pub const SSIM_RADIUS: usize = SSIM_WINDOW / 2;
/// Standard deviation of the Gaussian window, in pixels.
pub const SSIM_SIGMA: f64 = 1.5;
/// `(K1 * L)^2` with `K1 = 0.01` and data range `L = 1`.
pub const SSIM_C1: f64 = 0.01 * 0.01;
/// `(K2 * L)^2` with `K2 = 0.03` and data range `L = 1`.
pub const SSIM_C2: f64 = 0.03 * 0.03;

#[derive(Clone, Debug, thiserror::Error, PartialEq)]
pub enum MetricsError {
    #[error(
        "image sizes differ: {}x{}x{} vs {}x{}x{} (width x height x channels)",
        a.0, a.1, a.2, b.0, b.1, b.2
    )]
    SizeMismatch { a: (u32, u32, u32), b: (u32, u32, u32) },
    #[error("image buffer holds {len} samples but {width}x{height}x{channels} needs {expected}")]
    Malformed { width: u32, height: u32, channels: u32, len: usize, expected: usize },
    #[error("images are empty ({width}x{height}x{channels})")]
    Empty { width: u32, height: u32, channels: u32 },
    #[error("image {width}x{height} is smaller than the {window}x{window} SSIM window")]
    TooSmall { width: u32, height: u32, window: usize },
}

/// How [`gaussian_filter`] treats samples outside the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Border {
    /// Zero outside: PyTorch `conv2d` with zero padding (3DGS).
    Zero,
    /// Half-sample symmetric reflection: `scipy.ndimage` mode `reflect` (scikit-image).
    Reflect,
}

/// Peak signal-to-noise ratio for data range 1: `10 log10(1 / MSE)` over all samples of all
/// channels. Identical images have zero error and give `f64::INFINITY`.
pub fn psnr(a: &Image<f32>, b: &Image<f32>) -> Result<f64, MetricsError> {
    let mse = mse(a, b)?;
    if mse == 0.0 {
        return Ok(f64::INFINITY);
    }
    Ok(10.0 * (1.0 / mse).log10())
}

/// Mean squared difference over all samples, accumulated in f64.
pub fn mse(a: &Image<f32>, b: &Image<f32>) -> Result<f64, MetricsError> {
    check_pair(a, b)?;
    let sum: f64 = a
        .data
        .iter()
        .zip(&b.data)
        .map(|(&x, &y)| {
            let d = f64::from(x) - f64::from(y);
            d * d
        })
        .sum();
    Ok(sum / a.data.len() as f64)
}

/// SSIM as 3DGS computes it (zero-padded windows, mean of the full map over all channels).
pub fn ssim(a: &Image<f32>, b: &Image<f32>) -> Result<f64, MetricsError> {
    let map = ssim_map(a, b, Border::Zero)?;
    Ok(map.data.iter().sum::<f64>() / map.data.len() as f64)
}

/// SSIM with scikit-image's conventions (reflect border, 5-pixel crop, mean of per-channel means).
/// Like scikit-image, it refuses images smaller than the window in either dimension.
pub fn ssim_skimage(a: &Image<f32>, b: &Image<f32>) -> Result<f64, MetricsError> {
    check_pair(a, b)?;
    if (a.width as usize) < SSIM_WINDOW || (a.height as usize) < SSIM_WINDOW {
        return Err(MetricsError::TooSmall {
            width: a.width,
            height: a.height,
            window: SSIM_WINDOW,
        });
    }
    let map = ssim_map(a, b, Border::Reflect)?;
    let (w, h, ch) = (map.width as usize, map.height as usize, map.channels as usize);
    let r = SSIM_RADIUS;
    let per_channel = (0..ch).map(|c| {
        let mut sum = 0.0;
        for y in r..h - r {
            for x in r..w - r {
                sum += map.data[(y * w + x) * ch + c];
            }
        }
        sum / ((w - 2 * r) * (h - 2 * r)) as f64
    });
    Ok(per_channel.sum::<f64>() / ch as f64)
}

/// The per-pixel, per-channel SSIM map (same layout as the inputs), with local statistics from the
/// Gaussian window under `border`:
/// `((2 mu_a mu_b + C1)(2 sigma_ab + C2)) / ((mu_a^2 + mu_b^2 + C1)(sigma_a^2 + sigma_b^2 + C2))`,
/// where the (co)variances are the population ones, `E_w[ab] - mu_a mu_b`.
pub fn ssim_map(
    a: &Image<f32>,
    b: &Image<f32>,
    border: Border,
) -> Result<Image<f64>, MetricsError> {
    check_pair(a, b)?;
    let (w, h, ch) = (a.width as usize, a.height as usize, a.channels as usize);
    let mut out = Image::<f64>::new(a.width, a.height, a.channels);
    for c in 0..ch {
        let x: Vec<f64> = (0..w * h).map(|i| f64::from(a.data[i * ch + c])).collect();
        let y: Vec<f64> = (0..w * h).map(|i| f64::from(b.data[i * ch + c])).collect();
        let product =
            |p: &[f64], q: &[f64]| -> Vec<f64> { p.iter().zip(q).map(|(u, v)| u * v).collect() };
        let mu_x = gaussian_filter(&x, w, h, border);
        let mu_y = gaussian_filter(&y, w, h, border);
        let e_xx = gaussian_filter(&product(&x, &x), w, h, border);
        let e_yy = gaussian_filter(&product(&y, &y), w, h, border);
        let e_xy = gaussian_filter(&product(&x, &y), w, h, border);
        for i in 0..w * h {
            let (mx, my) = (mu_x[i], mu_y[i]);
            let var_x = e_xx[i] - mx * mx;
            let var_y = e_yy[i] - my * my;
            let cov = e_xy[i] - mx * my;
            let num = (2.0 * mx * my + SSIM_C1) * (2.0 * cov + SSIM_C2);
            let den = (mx * mx + my * my + SSIM_C1) * (var_x + var_y + SSIM_C2);
            out.data[i * ch + c] = num / den;
        }
    }
    Ok(out)
}

/// The normalised 1D Gaussian window: `exp(-k^2 / (2 sigma^2))` for `k = -5..=5`, divided by its
/// sum (as both 3DGS's `gaussian()` and scipy's `_gaussian_kernel1d` do).
pub fn gaussian_window() -> [f64; SSIM_WINDOW] {
    let mut g = [0.0; SSIM_WINDOW];
    for (i, v) in g.iter_mut().enumerate() {
        let k = i as f64 - SSIM_RADIUS as f64;
        *v = (-k * k / (2.0 * SSIM_SIGMA * SSIM_SIGMA)).exp();
    }
    let sum: f64 = g.iter().sum();
    g.map(|v| v / sum)
}

/// Correlate a single-channel `width x height` plane (row-major) with the 11x11 Gaussian window,
/// as two 1D passes: along each row, then along each column.
pub fn gaussian_filter(plane: &[f64], width: usize, height: usize, border: Border) -> Vec<f64> {
    let g = gaussian_window();
    let mut rows = vec![0.0; width * height];
    for y in 0..height {
        let line = &plane[y * width..(y + 1) * width];
        for x in 0..width {
            rows[y * width + x] = window_sum(&g, x, width, border, |i| line[i]);
        }
    }
    let mut out = vec![0.0; width * height];
    for x in 0..width {
        for y in 0..height {
            out[y * width + x] = window_sum(&g, y, height, border, |i| rows[i * width + x]);
        }
    }
    out
}

/// `sum_k g[k] * line[centre + k - R]` over a line of length `n`, with `border` outside it.
#[inline]
fn window_sum(
    g: &[f64; SSIM_WINDOW],
    centre: usize,
    n: usize,
    border: Border,
    line: impl Fn(usize) -> f64,
) -> f64 {
    let mut sum = 0.0;
    for (k, &gk) in g.iter().enumerate() {
        let i = centre as isize + k as isize - SSIM_RADIUS as isize;
        let v = if (0..n as isize).contains(&i) {
            line(i as usize)
        } else {
            match border {
                Border::Zero => 0.0,
                Border::Reflect => line(reflect(i, n)),
            }
        };
        sum += gk * v;
    }
    sum
}

/// scipy's `reflect` index: the line mirrored about its outer sample edges, repeated with period
/// `2n` (so it also holds when the window is wider than the line).
fn reflect(i: isize, n: usize) -> usize {
    let period = 2 * n as isize;
    let m = i.rem_euclid(period) as usize;
    if m < n { m } else { 2 * n - 1 - m }
}

fn check_pair(a: &Image<f32>, b: &Image<f32>) -> Result<(), MetricsError> {
    for im in [a, b] {
        let expected = im.width as usize * im.height as usize * im.channels as usize;
        if im.data.len() != expected {
            return Err(MetricsError::Malformed {
                width: im.width,
                height: im.height,
                channels: im.channels,
                len: im.data.len(),
                expected,
            });
        }
    }
    if (a.width, a.height, a.channels) != (b.width, b.height, b.channels) {
        return Err(MetricsError::SizeMismatch {
            a: (a.width, a.height, a.channels),
            b: (b.width, b.height, b.channels),
        });
    }
    if a.data.is_empty() {
        return Err(MetricsError::Empty { width: a.width, height: a.height, channels: a.channels });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reflect_matches_scipy_half_sample_symmetry() {
        // scipy reflect on [a b c d]: ... c d | d c b a | a b c d | d c b a | a b ...
        let got: Vec<usize> = (-6..10).map(|i| reflect(i, 4)).collect();
        assert_eq!(got, [2, 3, 3, 2, 1, 0, 0, 1, 2, 3, 3, 2, 1, 0, 0, 1]);
        assert!((-7..7).all(|i| reflect(i, 1) == 0));
    }

    #[test]
    fn window_is_normalised_and_symmetric() {
        let g = gaussian_window();
        assert!((g.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        for k in 0..SSIM_WINDOW {
            assert_eq!(g[k], g[SSIM_WINDOW - 1 - k]);
        }
        assert!(g[SSIM_RADIUS] > g[SSIM_RADIUS - 1]);
    }
}
