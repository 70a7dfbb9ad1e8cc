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

mod window_filter;
use window_filter::filter_rows;
pub use window_filter::{gaussian_filter, gaussian_window};

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
    #[error("the coverage mask is {width}x{height}, the images {image_width}x{image_height}")]
    CoverageSize { width: u32, height: u32, image_width: u32, image_height: u32 },
    #[error("no pixel is covered: nothing to score")]
    NothingCovered,
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
    Ok(psnr_of_mse(mse(a, b)?))
}

/// The PSNR of the mean squared error of images of one size, from their PSNRs (an infinite
/// one, no error, counts as zero error): a mean over views that stays finite when some view is
/// rendered exactly.
pub fn pooled_psnr(per_image: &[f64]) -> f64 {
    let mse: f64 = per_image.iter().map(|p| 10f64.powf(-p / 10.0)).sum::<f64>();
    psnr_of_mse(mse / per_image.len().max(1) as f64)
}

/// `10 log10(1 / mse)`, infinite for no error.
fn psnr_of_mse(mse: f64) -> f64 {
    if mse == 0.0 { f64::INFINITY } else { 10.0 * (1.0 / mse).log10() }
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

/// [`psnr`] over the pixels `covered` marks (nonzero; every pixel when None): a photo
/// undistorted into a pinhole view has corners no source pixel reaches, and counted as matches
/// they would raise the score by their share of the image.
pub fn psnr_covered(
    a: &Image<f32>,
    b: &Image<f32>,
    covered: Option<&Image<u8>>,
) -> Result<f64, MetricsError> {
    let Some(covered) = covered else { return psnr(a, b) };
    check_pair(a, b)?;
    let squared: Vec<f64> =
        a.data.iter().zip(&b.data).map(|(&x, &y)| (f64::from(x) - f64::from(y)).powi(2)).collect();
    Ok(psnr_of_mse(mean_over_covered(&squared, a, covered)?))
}

/// [`ssim`]'s map averaged over the pixels `covered` marks (every pixel when None).
pub fn ssim_covered(
    a: &Image<f32>,
    b: &Image<f32>,
    covered: Option<&Image<u8>>,
) -> Result<f64, MetricsError> {
    let Some(covered) = covered else { return ssim(a, b) };
    let map = ssim_map(a, b, Border::Zero)?;
    mean_over_covered(&map.data, a, covered)
}

/// The mean of `samples` (laid out as `image`'s) over the pixels `covered` marks.
fn mean_over_covered(
    samples: &[f64],
    image: &Image<f32>,
    covered: &Image<u8>,
) -> Result<f64, MetricsError> {
    let keep = covered_pixels(image, covered)?;
    let ch = image.channels.max(1) as usize;
    let (sum, count) = samples
        .iter()
        .enumerate()
        .filter(|(i, _)| keep[i / ch])
        .fold((0.0, 0usize), |(sum, count), (_, v)| (sum + v, count + 1));
    Ok(sum / count as f64)
}

/// Per pixel of `image`, whether `covered` marks it; an error when the sizes differ or nothing
/// is covered.
fn covered_pixels(image: &Image<f32>, covered: &Image<u8>) -> Result<Vec<bool>, MetricsError> {
    if (covered.width, covered.height) != (image.width, image.height) {
        return Err(MetricsError::CoverageSize {
            width: covered.width,
            height: covered.height,
            image_width: image.width,
            image_height: image.height,
        });
    }
    let cc = covered.channels.max(1) as usize;
    let keep: Vec<bool> = covered.data.chunks(cc).map(|c| c[0] != 0).collect();
    if !keep.iter().any(|&k| k) {
        return Err(MetricsError::NothingCovered);
    }
    Ok(keep)
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
        // The five windowed planes: a, b, a a, b b and a b, row by row.
        let source = |y: usize, lines: &mut [Vec<f64>; 5]| {
            let row = y * w * ch;
            for x in 0..w {
                let (u, v) =
                    (f64::from(a.data[row + x * ch + c]), f64::from(b.data[row + x * ch + c]));
                lines[0][x] = u;
                lines[1][x] = v;
                lines[2][x] = u * u;
                lines[3][x] = v * v;
                lines[4][x] = u * v;
            }
        };
        let emit = |m: &[Vec<f64>; 5], out_row: &mut [f64]| {
            for x in 0..w {
                let (mx, my) = (m[0][x], m[1][x]);
                let var_x = m[2][x] - mx * mx;
                let var_y = m[3][x] - my * my;
                let cov = m[4][x] - mx * my;
                let num = (2.0 * mx * my + SSIM_C1) * (2.0 * cov + SSIM_C2);
                let den = (mx * mx + my * my + SSIM_C1) * (var_x + var_y + SSIM_C2);
                out_row[x * ch + c] = num / den;
            }
        };
        filter_rows(w, h, border, &mut out.data, w * ch, source, emit);
    }
    Ok(out)
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
