//! Stage `prefix_sum`: exclusive scan of the tile counts taken in depth order (each Gaussian's first
//! slot in the key list) and the total.
pub fn prefix_sum(counts: &[u32]) -> (Vec<u32>, u32) {
    let mut offsets = Vec::with_capacity(counts.len());
    let mut total = 0u32;
    for &c in counts {
        offsets.push(total);
        total += c;
    }
    (offsets, total)
}
