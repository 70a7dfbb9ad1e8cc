//! The 11x11 Gaussian window of SSIM, applied as two 1D passes (along rows, then along
//! columns), which is exactly the 2D correlation with the outer-product window for either
//! [`Border`].
//!
//! [`filter_rows`] filters several planes at once, a run of output rows per core: each run
//! filters the rows it needs along x (its rows and a window's radius on either side) into its
//! own scratch, then adds whole scaled rows of that along y. Every output is summed over the
//! window in tap order, as a plain loop over the 2D index would, so the result does not depend
//! on the runs. One scratch per run and call, not a fresh image per plane and pass: an
//! evaluation filters five planes per channel of every test view while the GPU waits, and
//! freeing image-sized buffers in a multi-threaded process costs more than the filtering.
use super::{Border, SSIM_RADIUS, SSIM_SIGMA, SSIM_WINDOW};

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

/// Correlate a single-channel `width x height` plane (row-major) with the 11x11 Gaussian window.
pub fn gaussian_filter(plane: &[f64], width: usize, height: usize, border: Border) -> Vec<f64> {
    let mut out = vec![0.0; width * height];
    filter_rows(
        width,
        height,
        border,
        &mut out,
        width,
        |y, lines: &mut [Vec<f64>; 1]| {
            lines[0].copy_from_slice(&plane[y * width..(y + 1) * width]);
        },
        |filtered, row| row.copy_from_slice(&filtered[0]),
    );
    out
}

/// Filter `N` planes of `width x height` with the window, on all cores. `source(y, lines)` fills
/// row `y` of each plane (`lines[k]` holds `width` values); `emit(filtered, out_row)` receives
/// a row of every filtered plane and writes the same row of `out` (rows of `out_row_len` items).
pub(super) fn filter_rows<const N: usize>(
    width: usize,
    height: usize,
    border: Border,
    out: &mut [f64],
    out_row_len: usize,
    source: impl Fn(usize, &mut [Vec<f64>; N]) + Sync,
    emit: impl Fn(&[Vec<f64>; N], &mut [f64]) + Sync,
) {
    let rows_per_run = crate::parallel::rows_per_thread(height);
    filter_rows_in_runs(width, height, border, out, out_row_len, rows_per_run, source, emit);
}

/// [`filter_rows`] with runs of `rows_per_run` output rows.
#[allow(clippy::too_many_arguments)]
fn filter_rows_in_runs<const N: usize>(
    width: usize,
    height: usize,
    border: Border,
    out: &mut [f64],
    out_row_len: usize,
    rows_per_run: usize,
    source: impl Fn(usize, &mut [Vec<f64>; N]) + Sync,
    emit: impl Fn(&[Vec<f64>; N], &mut [f64]) + Sync,
) {
    debug_assert_eq!(out.len(), height * out_row_len);
    let g = gaussian_window();
    crate::parallel::for_each_run_mut(out, out_row_len, rows_per_run, |y0, run| {
        let y1 = y0 + run.len() / out_row_len.max(1);
        // Every source row an output row of the run reads, reflected ones included (they lie
        // within a radius of the image's edge, and so of the run's first or last row).
        let (lo, hi) = (y0.saturating_sub(SSIM_RADIUS), (y1 + SSIM_RADIUS).min(height));
        let mut lines: [Vec<f64>; N] = std::array::from_fn(|_| vec![0.0; width]);
        let mut along_x: [Vec<f64>; N] = std::array::from_fn(|_| vec![0.0; (hi - lo) * width]);
        for s in lo..hi {
            source(s, &mut lines);
            for (line, filtered) in lines.iter().zip(&mut along_x) {
                let at = (s - lo) * width;
                filter_line(&g, line, &mut filtered[at..at + width], border);
            }
        }
        let mut sums: [Vec<f64>; N] = std::array::from_fn(|_| vec![0.0; width]);
        for (y, out_row) in (y0..y1).zip(run.chunks_mut(out_row_len.max(1))) {
            for (sum, filtered) in sums.iter_mut().zip(&along_x) {
                sum.fill(0.0);
                for (k, &gk) in g.iter().enumerate() {
                    let i = y as isize + k as isize - SSIM_RADIUS as isize;
                    let s = if (0..height as isize).contains(&i) {
                        i as usize
                    } else {
                        match border {
                            // Adds nothing: the other taps' sum is the same without it.
                            Border::Zero => continue,
                            Border::Reflect => reflect(i, height),
                        }
                    };
                    let at = (s - lo) * width;
                    for (a, v) in sum.iter_mut().zip(&filtered[at..at + width]) {
                        *a += gk * v;
                    }
                }
            }
            emit(&sums, out_row);
        }
    });
}

/// One row along x: `out[x] = sum_k g[k] * line[x + k - R]`, the window read as a slice where it
/// lies inside the line, through [`window_sum`] at the ends.
fn filter_line(g: &[f64; SSIM_WINDOW], line: &[f64], out: &mut [f64], border: Border) {
    let n = line.len();
    for (x, o) in out.iter_mut().enumerate() {
        *o = if x >= SSIM_RADIUS && x + SSIM_RADIUS < n {
            let mut sum = 0.0;
            for (gk, v) in g.iter().zip(&line[x - SSIM_RADIUS..=x + SSIM_RADIUS]) {
                sum += gk * v;
            }
            sum
        } else {
            window_sum(g, x, n, border, |i| line[i])
        };
    }
}

/// `sum_k g[k] * line[centre + k - R]` over a line of length `n`, with `border` outside it.
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

    /// Runs of any length give the same bits, the image taller or shorter than the window: the
    /// rows a run reads about its ends (and reflects at the image's) are all filtered along x.
    #[test]
    fn the_runs_do_not_change_a_bit() {
        for (w, h) in [(17usize, 23usize), (9, 4), (3, 1)] {
            let plane: Vec<f64> = (0..w * h).map(|i| ((i * 37) % 23) as f64 / 23.0 - 0.3).collect();
            for border in [Border::Zero, Border::Reflect] {
                let run = |rows: usize| {
                    let mut out = vec![0.0; w * h * 2];
                    filter_rows_in_runs(
                        w,
                        h,
                        border,
                        &mut out,
                        2 * w,
                        rows,
                        |y, lines: &mut [Vec<f64>; 2]| {
                            for x in 0..w {
                                lines[0][x] = plane[y * w + x];
                                lines[1][x] = plane[y * w + x] * plane[y * w + x];
                            }
                        },
                        |f, row| {
                            row[..w].copy_from_slice(&f[0]);
                            row[w..].copy_from_slice(&f[1]);
                        },
                    );
                    out
                };
                let whole = run(h);
                for rows in [1, 2, 3, 5, 7] {
                    let got = run(rows);
                    let same = whole.iter().zip(&got).all(|(a, b)| a.to_bits() == b.to_bits());
                    assert!(same, "{w}x{h} {border:?}, runs of {rows}");
                }
            }
        }
    }
}
