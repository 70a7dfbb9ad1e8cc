//! Twin of `block_reach` in shaders/shared/block_walk.wgsl, in f32 as the GPU computes it: which
//! pixel blocks of a tile a projected Gaussian can reach with alpha >= 1/255. The GPU's
//! rasterize passes skip an entry for a block whose bit is clear, so the test must never clear a
//! bit that a pixel's own f32 evaluation would pass; the tests below check that against the
//! per-pixel evaluation on random and adversarial conics.
use crate::pipeline::{MAX_ALPHA, MIN_ALPHA, TILE_SIZE};

/// Bit k set when the Gaussian (conic a, b, c and opacity; mean in pixels) may reach block k of
/// the tile whose first pixel centre is `corner`, blocks of `block` pixels numbered row by row.
///
/// The test is the ellipse o G = MIN_ALPHA itself, not its bounding box: a bounding box keeps
/// every block of its corners, which for a round Gaussian is a fifth of the box and for a thin
/// diagonal one most of it, and the rasterize passes evaluate every pixel of a kept block. Per row
/// of blocks, the ellipse's x-range over the row's band of pixel centres: the ellipse's left edge
/// `L(y) = (-b y - sqrt(a r - det y^2)) / a` is convex in y, so its least value over the band is
/// the ellipse's leftmost point where that lies in the band and else at an end of the band (the
/// right edge likewise). The ellipse is widened by 2% about its centre (r times 1.02^2) and the
/// band and the range by 0.05 px plus 1e-6 of the coordinates: with the conic's condition number
/// under 1e4 the f32 rounding of an evaluation moves its exponent by well under 1% of r, which
/// the widening covers. Any other conic (ill-conditioned, not positive definite, not finite)
/// reaches every block.
pub fn block_reach(conic: [f32; 4], mean: [f32; 2], corner: [f32; 2], block: [u32; 2]) -> u32 {
    let per_row = TILE_SIZE / block[0];
    let rows = TILE_SIZE / block[1];
    let all = (1u32 << (per_row * rows)) - 1;
    let [a, b, c, o] = conic;
    let det = a * c - b * b;
    let r = 2.0 * (o / MIN_ALPHA as f32).ln() * 1.0404;
    let trace = a + c;
    let coords = mean[0].abs() + mean[1].abs();
    if !(det > 0.0) || !(a > 0.0) || !(r > 0.0) || !(trace * trace <= 1e4 * det) || !(coords <= 1e7)
    {
        return all;
    }
    let slack = 0.05 + 1e-6 * (coords + corner[0].abs() + corner[1].abs());
    // Half-extents, and the y of the leftmost point (the rightmost one's is its negative).
    let half = [(r * c / det).sqrt(), (r * a / det).sqrt()];
    let y_left = b * (r / (c * det)).sqrt();
    if !(half[0] < 1e30) || !(half[1] < 1e30) || !y_left.is_finite() {
        return all;
    }
    let edge = |y: f32, side: f32| (-b * y + side * (a * r - det * y * y).max(0.0).sqrt()) / a;
    let span = [(block[0] - 1) as f32, (block[1] - 1) as f32];
    let mut bits = 0;
    for row in 0..rows {
        // The row's band of pixel centres, relative to the mean, within the ellipse's extent.
        let top = corner[1] + (row * block[1]) as f32 - mean[1];
        let y0 = (top - slack).max(-half[1]);
        let y1 = (top + span[1] + slack).min(half[1]);
        if !(y0 <= y1) {
            continue;
        }
        let left = if y0 <= y_left && y_left <= y1 {
            -half[0]
        } else {
            edge(y0, -1.0).min(edge(y1, -1.0))
        };
        let right =
            if y0 <= -y_left && -y_left <= y1 { half[0] } else { edge(y0, 1.0).max(edge(y1, 1.0)) };
        let (lo, hi) = (mean[0] + left - slack, mean[0] + right + slack);
        for column in 0..per_row {
            let first = corner[0] + (column * block[0]) as f32;
            if hi >= first && lo <= first + span[0] {
                bits |= 1 << (row * per_row + column);
            }
        }
    }
    bits
}

/// Whether the GPU's f32 `alpha_at` passes at pixel centre `p` (its exact arithmetic order).
pub fn reaches_f32(conic: [f32; 4], mean: [f32; 2], p: [f32; 2]) -> bool {
    let [a, b, c, o] = conic;
    let (dx, dy) = (p[0] - mean[0], p[1] - mean[1]);
    let power = -0.5 * (a * dx * dx + c * dy * dy) - b * dx * dy;
    if !(power <= 0.0) {
        return false;
    }
    let alpha = (o * power.exp()).min(MAX_ALPHA as f32);
    alpha >= MIN_ALPHA as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// Every pixel of every block: a pixel that passes lies in a block whose bit is set.
    fn check(conic: [f32; 4], mean: [f32; 2], corner: [f32; 2], block: [u32; 2]) -> usize {
        let bits = block_reach(conic, mean, corner, block);
        let per_row = TILE_SIZE / block[0];
        let mut passing = 0;
        for y in 0..TILE_SIZE {
            for x in 0..TILE_SIZE {
                let p = [corner[0] + x as f32, corner[1] + y as f32];
                if reaches_f32(conic, mean, p) {
                    passing += 1;
                    let k = (y / block[1]) * per_row + x / block[0];
                    assert!(
                        bits & (1 << k) != 0,
                        "conic {conic:?} mean {mean:?} corner {corner:?} block {block:?}: pixel \
                         ({x}, {y}) passes but block {k} is cleared (bits {bits:#b})"
                    );
                }
            }
        }
        passing
    }

    /// A conic from the 2D covariance of scales (sx, sy), rotation `angle` and the blur, in f32
    /// as project computes it.
    fn conic(sx: f64, sy: f64, angle: f64, o: f64) -> [f32; 4] {
        let (s, c) = angle.sin_cos();
        let (xx, yy) = (sx * sx, sy * sy);
        let a = (c * c * xx + s * s * yy + 0.3) as f32;
        let b = (c * s * (xx - yy)) as f32;
        let cc = (s * s * xx + c * c * yy + 0.3) as f32;
        let det = a * cc - b * b;
        [cc / det, -b / det, a / det, o as f32]
    }

    #[test]
    fn block_reach_never_clears_a_reached_block() {
        let mut rng = Rng::new(31);
        let mut passing = 0;
        let mut cleared = 0;
        for i in 0..20_000 {
            // Scales from a tenth of a pixel to hundreds, thin and round, any opacity.
            let sx = 10f64.powf(rng.range(-1.0, 2.5));
            let sy = if i % 3 == 0 { sx } else { 10f64.powf(rng.range(-1.0, 2.5)) };
            let o = rng.range(0.003, 1.0);
            let k = conic(sx, sy, rng.range(0.0, 3.2), o);
            let corner = [
                (rng.range(0.0, 400.0).floor() * 8.0 + 0.5) as f32,
                (rng.range(0.0, 400.0).floor() * 8.0 + 0.5) as f32,
            ];
            let reach = 3.5 * sx.max(sy) + 8.0;
            let mean = [
                corner[0] + rng.range(-reach, reach + 8.0) as f32,
                corner[1] + rng.range(-reach, reach + 8.0) as f32,
            ];
            for block in [[4, 2], [8, 4], [8, 1]] {
                passing += check(k, mean, corner, block);
                cleared += (block_reach(k, mean, corner, block)
                    ^ ((1 << (TILE_SIZE * TILE_SIZE / (block[0] * block[1]))) - 1))
                    .count_ones();
            }
        }
        // The test exercised both sides: pixels that pass and blocks skipped.
        assert!(passing > 100_000 && cleared > 100_000, "passing {passing}, cleared {cleared}");
    }

    #[test]
    fn blocks_in_the_bounding_box_but_off_the_ellipse_are_cleared() {
        let corner = [8.5, 16.5];
        let centre = TILE_SIZE as f32 / 2.0 - 0.5;
        // Long and thin along the tile's diagonal (positive correlation: top left to bottom
        // right): its bounding box is the whole tile, but it passes several pixels from the
        // top-right and bottom-left corners.
        let thin = conic(40.0, 0.5, std::f64::consts::FRAC_PI_4, 0.9);
        let mean = [corner[0] + centre, corner[1] + centre];
        let (per_row, rows) = (TILE_SIZE / 2, TILE_SIZE / 2);
        let bits = block_reach(thin, mean, corner, [2, 2]);
        assert!(check(thin, mean, corner, [2, 2]) >= TILE_SIZE as usize, "the diagonal passes");
        for k in [0, rows * per_row - 1] {
            assert!(bits & (1 << k) != 0, "block {k} on the diagonal: {bits:#b}");
        }
        for k in [per_row - 1, (rows - 1) * per_row] {
            assert!(bits & (1 << k) == 0, "corner block {k} off the diagonal: {bits:#b}");
        }
        // A disc of radius ~10 px centred 8 px up and left of the tile's first pixel: its box
        // reaches over the first block, the disc itself stops 1 px short of it.
        let round = conic(3.0, 3.0, 0.0, 0.9);
        let mean = [corner[0] - 8.0, corner[1] - 8.0];
        assert_eq!(check(round, mean, corner, [4, 2]), 0);
        assert_eq!(block_reach(round, mean, corner, [4, 2]), 0);
    }

    #[test]
    fn block_reach_keeps_every_block_for_bad_conics() {
        let corner = [8.5, 16.5];
        let mean = [10.0, 18.0];
        let all = (1 << 8) - 1;
        for bad in [
            [f32::NAN, 0.0, 1.0, 0.5],
            [1.0, 2.0, 1.0, 0.5],   // not positive definite
            [-1.0, 0.0, -1.0, 0.5], // negative
            [1e6, 0.0, 1e-4, 0.5],  // condition number 1e10
            [f32::INFINITY, 0.0, 1.0, 0.5],
            [1.0, 0.0, 1.0, f32::NAN],
        ] {
            assert_eq!(block_reach(bad, mean, corner, [4, 2]), all, "{bad:?}");
        }
        assert_eq!(block_reach([1.0, 0.0, 1.0, 0.5], [1e9, 0.0], corner, [4, 2]), all);
    }
}
