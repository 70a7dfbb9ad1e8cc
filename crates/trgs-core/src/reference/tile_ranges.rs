//! Stage `tile_ranges`: for each tile, the half-open range of its entries in the sorted list.
pub fn tile_ranges(sorted_keys: &[u64], tile_count: u32) -> Vec<(u32, u32)> {
    let mut ranges = vec![(0u32, 0u32); tile_count as usize];
    for (slot, &k) in sorted_keys.iter().enumerate() {
        let tile = (k >> 32) as usize;
        let slot = slot as u32;
        if slot == 0 || (sorted_keys[slot as usize - 1] >> 32) as usize != tile {
            ranges[tile].0 = slot;
        }
        ranges[tile].1 = slot + 1;
    }
    ranges
}
