//! PSNR and SSIM against scikit-image and a numpy/scipy mirror of 3DGS's SSIM.
use trgs_core::Image;
use trgs_core::metrics::{
    Border, MetricsError, gaussian_filter, mse, psnr, psnr_covered, ssim, ssim_covered, ssim_map,
    ssim_skimage,
};

fn base(x: i64, y: i64, c: i64) -> i64 {
    (x * 37 + y * 91 + c * 13 + (x * y) % 17) % 256
}

fn hash8(x: i64, y: i64, c: i64) -> i64 {
    (((x * 7919 + y * 6271 + c * 3037 + x * y * 31) * 2_654_435_761) & 0xFFFF_FFFF) >> 24
}

/// The image pairs of `tests/fixtures/metrics_reference.py::pair`, sample for sample: integer
/// levels k in [0, 255], stored as the f32 `k / 255` (correctly rounded in both languages).
fn pair(name: &str, w: u32, h: u32, ch: u32) -> (Image<f32>, Image<f32>) {
    let (mut a, mut b) = (Image::new(w, h, ch), Image::new(w, h, ch));
    for y in 0..h {
        for x in 0..w {
            for c in 0..ch {
                let (xi, yi, ci) = (i64::from(x), i64::from(y), i64::from(c));
                let n = hash8(xi, yi, ci);
                let mut ka = base(xi, yi, ci);
                let kb = match name {
                    "textured_rgb" => {
                        ((3 * ka + base(xi + 2, yi + 1, ci)) / 4 + n % 41 - 20).clamp(0, 255)
                    }
                    "noisy_gray" => (ka + n % 21 - 10).clamp(0, 255),
                    "unrelated_rgb" => (xi * xi * 5 + yi * yi * 3 + ci * 101 + n) % 256,
                    "smooth_rgba" => {
                        ka = (xi * 16 + yi * 4 + ci * 40) % 256;
                        (ka + n % 9 - 4).clamp(0, 255)
                    }
                    _ => panic!("unknown pair {name}"),
                };
                a.set(x, y, c, ka as f32 / 255.0);
                b.set(x, y, c, kb as f32 / 255.0);
            }
        }
    }
    (a, b)
}

/// Reference values printed by `python3 crates/trgs-core/tests/fixtures/metrics_reference.py` with
/// numpy 2.4.6, scipy 1.17.1, scikit-image 0.26.0 (Python 3.11.7).
/// Columns: name, width, height, channels, then
/// - psnr_f64: skimage `peak_signal_noise_ratio(data_range=1)` on the float32 values upcast to f64,
/// - psnr_f32: the same on the float32 images (skimage subtracts in float32),
/// - ssim_skimage_f64: skimage `structural_similarity(channel_axis=-1, gaussian_weights=True,
///   sigma=1.5, use_sample_covariance=False, data_range=1.0)` on the f64 upcast (computed in f64),
/// - ssim_skimage_f32: the same on the float32 images (skimage then filters in float32),
/// - ssim_3dgs_f64: 3DGS's SSIM mirrored with `scipy.ndimage.correlate(mode='constant')` in f64.
const REFERENCE: [(&str, u32, u32, u32, [f64; 5]); 4] = [
    (
        "textured_rgb",
        64,
        48,
        3,
        [
            17.805886889215948,
            17.805886840771464,
            0.8713341713474719,
            0.8713341355323792,
            0.8809220522671521,
        ],
    ),
    (
        "noisy_gray",
        33,
        17,
        1,
        [
            32.48914512280179,
            32.489145086430035,
            0.9968578084786253,
            0.996857762336731,
            0.9972288515215862,
        ],
    ),
    (
        "unrelated_rgb",
        40,
        30,
        3,
        [
            7.697902895406195,
            7.6979028109686745,
            -0.00012759299743471267,
            -0.00012761021207552403,
            0.10568065500941395,
        ],
    ),
    (
        "smooth_rgba",
        16,
        12,
        4,
        [
            40.18650393499062,
            40.186503956053066,
            0.997251189736641,
            0.9972513318061829,
            0.9983166454317418,
        ],
    ),
];

#[test]
fn metrics_match_scikit_image_and_the_3dgs_definition() {
    for (name, w, h, c, [psnr64, psnr32, sk64, sk32, gs64]) in REFERENCE {
        let (a, b) = pair(name, w, h, c);
        let p = psnr(&a, &b).expect("same size");
        let s = ssim(&a, &b).expect("same size");
        let k = ssim_skimage(&a, &b).expect("same size");
        eprintln!(
            "{name}: psnr {p:.12} (d64 {:.1e}, d32 {:.1e}), ssim_skimage {k:.12} (d64 {:.1e}, \
             d32 {:.1e}), ssim {s:.12} (d {:.1e})",
            p - psnr64,
            p - psnr32,
            k - sk64,
            k - sk32,
            s - gs64
        );
        // The f64 references use the same arithmetic: agreement to rounding.
        assert!((p - psnr64).abs() < 1e-10, "{name}: psnr {p} vs {psnr64}");
        assert!((k - sk64).abs() < 1e-10, "{name}: ssim_skimage {k} vs {sk64}");
        assert!((s - gs64).abs() < 1e-10, "{name}: ssim {s} vs {gs64}");
        // scikit-image's own float32 pipeline: within its single-precision rounding.
        assert!((p - psnr32).abs() < 1e-4, "{name}: psnr {p} vs f32 {psnr32}");
        assert!((k - sk32).abs() < 1e-4, "{name}: ssim_skimage {k} vs f32 {sk32}");
    }
}

#[test]
fn identical_images_are_perfect() {
    let (a, _) = pair("textured_rgb", 64, 48, 3);
    assert_eq!(psnr(&a, &a), Ok(f64::INFINITY));
    assert!((ssim(&a, &a).expect("same size") - 1.0).abs() < 1e-12);
    assert!((ssim_skimage(&a, &a).expect("same size") - 1.0).abs() < 1e-12);
}

#[test]
fn psnr_of_a_constant_offset() {
    let a = Image::filled(5, 4, 3, 0.25f32);
    let b = Image::filled(5, 4, 3, 0.35f32);
    let d = f64::from(0.35f32) - f64::from(0.25f32);
    assert_eq!(mse(&a, &b), Ok(d * d));
    assert!((psnr(&a, &b).expect("same size") - 20.0).abs() < 1e-5);
}

/// Uncovered pixels (an undistorted photo's empty corners, zero in render and photo alike) do
/// not count: the score is that of the covered ones alone, not raised by the matching zeros.
#[test]
fn only_covered_pixels_are_scored() {
    let (w, h) = (40u32, 30u32);
    let (a, b) = pair("textured_rgb", w, h, 3);
    // The left quarter uncovered, zero in both images.
    let mask = |w: u32, h: u32, on: &dyn Fn(u32) -> bool| {
        let mut m = Image::<u8>::new(w, h, 1);
        for y in 0..h {
            for x in 0..w {
                m.set(x, y, 0, u8::from(on(x)));
            }
        }
        m
    };
    let covered = mask(w, h, &|x| x >= w / 4);
    let (a, b) = (a.zero_uncovered(&covered), b.zero_uncovered(&covered));
    let right = |im: &Image<f32>| im.columns(w / 4, w);
    let expected = psnr(&right(&a), &right(&b)).expect("same size");
    let scored = psnr_covered(&a, &b, Some(&covered)).expect("covered");
    assert!((scored - expected).abs() < 1e-9, "{scored} vs {expected}");
    // Counting the zeros as matches raises the PSNR by 10 log10(4/3).
    let all = psnr(&a, &b).expect("same size");
    assert!((all - scored - 10.0 * (4.0f64 / 3.0).log10()).abs() < 1e-9);
    assert_eq!(psnr_covered(&a, &b, None), psnr(&a, &b));
    assert_eq!(ssim_covered(&a, &b, None), ssim(&a, &b));
    // SSIM: the mean of 3DGS's map over the covered pixels' samples.
    let map = ssim_map(&a, &b, Border::Zero).expect("same size");
    let kept: Vec<f64> = (0..h)
        .flat_map(|y| (w / 4..w).flat_map(move |x| (0..3).map(move |c| (x, y, c))))
        .map(|(x, y, c)| map.get(x, y, c))
        .collect();
    let expected = kept.iter().sum::<f64>() / kept.len() as f64;
    let scored = ssim_covered(&a, &b, Some(&covered)).expect("covered");
    assert!((scored - expected).abs() < 1e-12, "{scored} vs {expected}");
    assert!(scored < ssim(&a, &b).expect("ssim"), "the zeroed corner's perfect SSIM left out");
    let nothing = mask(w, h, &|_| false);
    assert_eq!(psnr_covered(&a, &b, Some(&nothing)), Err(MetricsError::NothingCovered));
    let small = mask(w - 1, h, &|_| true);
    assert!(matches!(ssim_covered(&a, &b, Some(&small)), Err(MetricsError::CoverageSize { .. })));
}

#[test]
fn size_mismatch_and_malformed_buffers_are_errors() {
    let a = Image::<f32>::new(12, 12, 3);
    for b in [Image::new(12, 13, 3), Image::new(13, 12, 3), Image::new(12, 12, 1)] {
        let want =
            MetricsError::SizeMismatch { a: (12, 12, 3), b: (b.width, b.height, b.channels) };
        assert_eq!(psnr(&a, &b), Err(want.clone()));
        assert_eq!(ssim(&a, &b), Err(want.clone()));
        assert_eq!(ssim_skimage(&a, &b), Err(want.clone()));
        assert!(want.to_string().contains("12x12x3 vs"), "{want}");
    }
    let mut bad = a.clone();
    bad.data.pop();
    assert!(matches!(psnr(&a, &bad), Err(MetricsError::Malformed { len: 431, .. })));
    let empty = Image::<f32>::new(0, 4, 3);
    assert!(matches!(ssim(&empty, &empty), Err(MetricsError::Empty { .. })));
    // scikit-image refuses images smaller than the window; 3DGS's zero padding does not.
    let small = Image::<f32>::filled(10, 20, 1, 0.5);
    assert!(matches!(ssim_skimage(&small, &small), Err(MetricsError::TooSmall { .. })));
    assert!((ssim(&small, &small).expect("any size") - 1.0).abs() < 1e-12);
}

#[test]
fn separable_filter_equals_the_2d_window() {
    let (w, h) = (13usize, 9usize);
    let plane: Vec<f64> = (0..w * h).map(|i| ((i * 37) % 23) as f64 / 23.0).collect();
    let g = trgs_core::metrics::gaussian_window();
    for border in [Border::Zero, Border::Reflect] {
        let fast = gaussian_filter(&plane, w, h, border);
        for y in 0..h {
            for x in 0..w {
                let mut sum = 0.0;
                for (j, gj) in g.iter().enumerate() {
                    for (i, gi) in g.iter().enumerate() {
                        let (sx, sy) = (x as isize + i as isize - 5, y as isize + j as isize - 5);
                        let v = match border {
                            Border::Zero if sx < 0 || sy < 0 => 0.0,
                            Border::Zero if sx >= w as isize || sy >= h as isize => 0.0,
                            _ => {
                                // Half-sample reflection, one bounce suffices here (5 < 9).
                                let r = |s: isize, n: isize| {
                                    if s < 0 {
                                        -s - 1
                                    } else if s >= n {
                                        2 * n - 1 - s
                                    } else {
                                        s
                                    }
                                };
                                plane[r(sy, h as isize) as usize * w + r(sx, w as isize) as usize]
                            }
                        };
                        sum += gi * gj * v;
                    }
                }
                assert!((fast[y * w + x] - sum).abs() < 1e-14, "{border:?} ({x}, {y})");
            }
        }
    }
}

#[test]
fn ssim_map_has_the_input_layout() {
    let (a, b) = pair("smooth_rgba", 16, 12, 4);
    let map = ssim_map(&a, &b, Border::Zero).expect("same size");
    assert_eq!((map.width, map.height, map.channels), (16, 12, 4));
    let mean = map.data.iter().sum::<f64>() / map.data.len() as f64;
    assert_eq!(mean, ssim(&a, &b).expect("same size"));
    assert!(map.data.iter().all(|v| v.is_finite() && *v <= 1.0 + 1e-12));
}

#[test]
fn pooled_psnr_counts_a_perfect_view_as_no_error() {
    use trgs_core::metrics::pooled_psnr;
    assert!((pooled_psnr(&[20.0, 20.0]) - 20.0).abs() < 1e-9);
    assert!((pooled_psnr(&[20.0, f64::INFINITY]) - 23.0103).abs() < 1e-3);
    assert!(pooled_psnr(&[f64::INFINITY]).is_infinite());
}
