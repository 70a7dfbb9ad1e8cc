//! Stage `tile_ranges`: for each tile, the half-open range of its entries in the sorted list.
pub fn tile_ranges(sorted_tiles: &[u32], tile_count: u32) -> Vec<(u32, u32)> {
    let mut ranges = vec![(0u32, 0u32); tile_count as usize];
    for (slot, &tile) in sorted_tiles.iter().enumerate() {
        let slot = slot as u32;
        if slot == 0 || sorted_tiles[slot as usize - 1] != tile {
            ranges[tile as usize].0 = slot;
        }
        ranges[tile as usize].1 = slot + 1;
    }
    ranges
}
