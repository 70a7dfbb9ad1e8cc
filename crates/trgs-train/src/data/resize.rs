//! Photos resampled to the training size with an area (box) filter.
use trgs_core::Image;

/// Resample an 8-bit image (samples k / 255) to [0, 1] with an area (box) filter: each output
/// pixel averages the input area it covers, partial pixels weighted by their overlap. Identity
/// (but for the scaling to [0, 1]) when the size is unchanged.
pub fn resize_area_u8(im: &Image<u8>, w: u32, h: u32) -> Image<f32> {
    if (im.width, im.height) == (w, h) {
        return im.to_f32();
    }
    // The 256 values once, not a division per sample read (each is read for about two output
    // pixels): the same values, so the same image.
    let value: [f64; 256] = std::array::from_fn(|k| k as f64 / 255.0);
    area_resample(im, w, h, |v| value[usize::from(v)])
}

fn area_resample<T: Copy>(im: &Image<T>, w: u32, h: u32, value: impl Fn(T) -> f64) -> Image<f32> {
    let ch = im.channels as usize;
    let sx = f64::from(im.width) / f64::from(w);
    let sy = f64::from(im.height) / f64::from(h);
    let spans = |n: u32, s: f64, limit: u32| -> Vec<Vec<(u32, f64)>> {
        (0..n)
            .map(|o| {
                let (a, b) = (f64::from(o) * s, f64::from(o + 1) * s);
                let (first, last) = (a.floor() as u32, (b.ceil() as u32).min(limit));
                (first..last)
                    .map(|i| (i, (b.min(f64::from(i + 1)) - a.max(f64::from(i))).max(0.0)))
                    .filter(|&(_, wgt)| wgt > 0.0)
                    .collect()
            })
            .collect()
    };
    let xs = spans(w, sx, im.width);
    let ys = spans(h, sy, im.height);
    let (source_row, out_row) = (im.width as usize * ch, w as usize * ch);
    let mut out = Image::<f32>::new(w, h, im.channels);
    // An output row at a time, so that nothing is allocated per pixel; each output sample is
    // still summed over the rows of its area, then the columns, as a loop per pixel would.
    let mut sums = vec![0.0f64; out_row];
    let mut totals = vec![0.0f64; w as usize];
    for (yspan, out) in ys.iter().zip(out.data.chunks_exact_mut(out_row.max(1))) {
        sums.fill(0.0);
        totals.fill(0.0);
        for &(iy, wy) in yspan {
            let row = &im.data[iy as usize * source_row..][..source_row];
            for ((xspan, sum), total) in xs.iter().zip(sums.chunks_exact_mut(ch)).zip(&mut totals) {
                for &(ix, wx) in xspan {
                    let wgt = wx * wy;
                    *total += wgt;
                    for (a, &v) in sum.iter_mut().zip(&row[ix as usize * ch..][..ch]) {
                        *a += wgt * value(v);
                    }
                }
            }
        }
        for ((o, sum), total) in out.chunks_exact_mut(ch).zip(sums.chunks_exact(ch)).zip(&totals) {
            for (o, a) in o.iter_mut().zip(sum) {
                *o = (a / total) as f32;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The filter on f32 samples, to check it on values that are not multiples of 1 / 255.
    fn resize_area(im: &Image<f32>, w: u32, h: u32) -> Image<f32> {
        area_resample(im, w, h, f64::from)
    }

    #[test]
    fn area_resize_averages_blocks_and_keeps_the_mean() {
        let mut im = Image::<f32>::new(4, 2, 1);
        im.data = vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0];
        let half = resize_area(&im, 2, 1);
        assert_eq!(half.data, vec![2.5, 4.5]);
        // A non-integer factor keeps the image mean.
        let odd = resize_area(&im, 3, 2);
        let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
        assert!((mean(&odd.data) - mean(&im.data)).abs() < 1e-5);
    }
}
