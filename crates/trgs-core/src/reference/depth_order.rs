//! Stage `depth_order`: the Gaussians that touch at least one tile, front to back. Keys are
//! emitted in this order and then sorted by tile alone, stably, so every tile's list comes out
//! front to back without sorting the depth bits of every key: a Gaussian's depth is sorted once,
//! however many tiles it touches. Ties in depth go to the lower index, as on the GPU (it lists
//! the entries in index order, then sorts them stably by depth).
use super::Projected;

/// Indices of the Gaussians with a non-zero tile count, sorted by (f32 depth bits, index).
pub fn depth_order(p: &Projected, counts: &[u32]) -> Vec<u32> {
    let mut order: Vec<(u32, u32)> = (0..p.len())
        .filter(|&i| counts[i] > 0)
        .map(|i| ((p.depth[i] as f32).to_bits(), i as u32))
        .collect();
    order.sort_unstable();
    order.into_iter().map(|(_, i)| i).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn front_to_back_ties_by_index_and_untouched_left_out() {
        let mut p = Projected::with_len(5);
        p.depth = vec![3.0, 1.0, 2.0, 1.0, 0.5];
        let counts = [1, 2, 1, 1, 0];
        assert_eq!(depth_order(&p, &counts), vec![1, 3, 2, 0]);
    }
}
