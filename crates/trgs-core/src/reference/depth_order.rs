//! Stage `depth_order`: the Gaussians that touch at least one tile, front to back. Keys are
//! emitted in this order and then sorted by tile alone, stably, so every tile's list comes out
//! front to back without sorting the depth bits of every key: a Gaussian's depth is sorted once,
//! however many tiles it touches. Ties in depth go to the lower index, as on the GPU (it lists
//! the entries in index order, then sorts them stably by depth).
//!
//! The sort key is [`depth_key`]: the f32 depth bits counted from the near plane's, which orders
//! every depth the projection keeps exactly as the depth does and fits in [`DEPTH_KEY_BITS`]
//! bits, so the GPU's radix sort needs one pass fewer than for the raw 32 bits.
use super::Projected;
use crate::pipeline::{DEPTH_KEY_BITS, depth_key_base};

/// The depth-order key of a depth: its f32 bits minus `base`'s ([`depth_key_base`]). The bits
/// of positive floats grow with them, 2^23 per octave, so the difference keeps their order and
/// stays below 2^30 up to 2^128 times the base; depths past that (and a NaN) all get the largest
/// key, depths below the base (the projection keeps none) the smallest. Ties go to the lower
/// entry, as every tie does.
pub fn depth_key(depth: f32, base: u32) -> u32 {
    const MAX: u32 = (1 << DEPTH_KEY_BITS) - 1;
    let bits = depth.to_bits();
    if bits >= 0x8000_0000 {
        // Negative (or -0, -NaN): below any projected depth.
        return 0;
    }
    bits.saturating_sub(base).min(MAX)
}

/// Indices of the Gaussians with a non-zero tile count, sorted by ([`depth_key`] of their f32
/// depth, index), for a view whose near plane is at `near`.
pub fn depth_order(p: &Projected, counts: &[u32], near: f64) -> Vec<u32> {
    let base = depth_key_base(near);
    let mut order: Vec<(u32, u32)> = (0..p.len())
        .filter(|&i| counts[i] > 0)
        .map(|i| (depth_key(p.depth[i] as f32, base), i as u32))
        .collect();
    order.sort_unstable();
    order.into_iter().map(|(_, i)| i).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::DEPTH_KEY_FLOOR;

    #[test]
    fn front_to_back_ties_by_index_and_untouched_left_out() {
        let mut p = Projected::with_len(5);
        p.depth = vec![3.0, 1.0, 2.0, 1.0, 0.5];
        let counts = [1, 2, 1, 1, 0];
        assert_eq!(depth_order(&p, &counts, 0.2), vec![1, 3, 2, 0]);
    }

    #[test]
    fn keys_keep_the_order_of_every_depth_past_near() {
        let base = depth_key_base(0.01);
        let depths = [0.01f32, 0.010_000_001, 0.5, 1.0, 1.000_000_1, 7.5, 1e6, 1e30, 1e36];
        let keys: Vec<u32> = depths.iter().map(|&d| depth_key(d, base)).collect();
        assert!(keys.windows(2).all(|w| w[0] < w[1]), "strictly increasing: {keys:?}");
        assert!(keys.iter().all(|&k| k < 1 << DEPTH_KEY_BITS));
        assert_eq!(keys[0], 0);
        // Past 2^128 times the base, and NaN or infinity: the largest key; below it: zero.
        let max = (1 << DEPTH_KEY_BITS) - 1;
        for d in [f32::MAX, f32::INFINITY, f32::NAN] {
            assert_eq!(depth_key(d, base), max, "{d}");
        }
        for d in [0.005f32, 0.0, -0.0, -1.0, f32::NEG_INFINITY] {
            assert_eq!(depth_key(d, base), 0, "{d}");
        }
    }

    #[test]
    fn a_tiny_near_plane_keys_from_the_floor() {
        assert_eq!(depth_key_base(1e-30), DEPTH_KEY_FLOOR.to_bits());
        assert_eq!(depth_key_base(0.2), 0.2f32.to_bits());
        let base = depth_key_base(1e-30);
        // Still ordered across the useful range of depths.
        let keys: Vec<u32> = [1e-6f32, 0.1, 1.0, 100.0, 1e15].map(|d| depth_key(d, base)).to_vec();
        assert!(keys.windows(2).all(|w| w[0] < w[1]), "{keys:?}");
    }
}
