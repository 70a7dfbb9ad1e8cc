//! Twin of `block_reach` in shaders/shared/block_walk.wgsl, in f32 as the GPU computes it: which
//! pixel blocks of a tile a projected Gaussian can reach with alpha >= 1/255. The GPU's
//! rasterize passes skip an entry for a block whose bit is clear, so the test must never clear a
//! bit that a pixel's own f32 evaluation would pass; the tests below check that against the
//! per-pixel evaluation on random and adversarial conics.
use crate::pipeline::{MAX_ALPHA, MIN_ALPHA, TILE_SIZE};

/// Bit k set when the Gaussian (conic a, b, c and opacity; mean in pixels) may reach block k of
/// the tile whose first pixel centre is `corner`, blocks of `block` pixels numbered row by row.
pub fn block_reach(conic: [f32; 4], mean: [f32; 2], corner: [f32; 2], block: [u32; 2]) -> u32 {
    let per_row = TILE_SIZE / block[0];
    let blocks = per_row * (TILE_SIZE / block[1]);
    let all = (1u32 << blocks) - 1;
    let [a, b, c, o] = conic;
    let det = a * c - b * b;
    let r = 2.0 * (o / MIN_ALPHA as f32).ln();
    let trace = a + c;
    let coords = mean[0].abs() + mean[1].abs();
    if !(det > 0.0) || !(a > 0.0) || !(r > 0.0) || !(trace * trace <= 1e4 * det) || !(coords <= 1e7)
    {
        return all;
    }
    let slack = 0.05 + 1e-6 * (coords + corner[0].abs() + corner[1].abs());
    let half = [(r * c / det).sqrt() * 1.02 + slack, (r * a / det).sqrt() * 1.02 + slack];
    if !(half[0] < 1e30) || !(half[1] < 1e30) {
        return all;
    }
    let span = [(block[0] - 1) as f32, (block[1] - 1) as f32];
    let mut bits = 0;
    for k in 0..blocks {
        let first = [
            corner[0] + ((k % per_row) * block[0]) as f32,
            corner[1] + ((k / per_row) * block[1]) as f32,
        ];
        let x = mean[0] + half[0] >= first[0] && mean[0] - half[0] <= first[0] + span[0];
        let y = mean[1] + half[1] >= first[1] && mean[1] - half[1] <= first[1] + span[1];
        if x && y {
            bits |= 1 << k;
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
