//! Stage `emit_keys`: one (tile, depth) key per Gaussian and touched tile. The key is
//! `tile << 32 | bits(depth as f32)`: depths are positive, so their IEEE bits sort like the
//! numbers, and a radix sort of the u64 orders by tile, then front to back.
use super::{Projected, TileGrid, TileRect, tile_rect};

/// Keys and values (Gaussian indices), written at each Gaussian's offset from `prefix_sum`.
pub fn emit_keys(
    p: &Projected,
    grid: &TileGrid,
    limit: &TileRect,
    offsets: &[u32],
    total: u32,
) -> (Vec<u64>, Vec<u32>) {
    let mut keys = vec![0u64; total as usize];
    let mut values = vec![0u32; total as usize];
    for i in 0..p.len() {
        if !p.visible[i] {
            continue;
        }
        let r = tile_rect(p.mean2d[i], p.extent[i], grid, limit);
        let depth_bits = u64::from((p.depth[i] as f32).to_bits());
        let mut slot = offsets[i] as usize;
        for ty in r.y0..r.y1 {
            for tx in r.x0..r.x1 {
                let tile = u64::from(ty * grid.tiles_x + tx);
                keys[slot] = tile << 32 | depth_bits;
                values[slot] = i as u32;
                slot += 1;
            }
        }
    }
    (keys, values)
}
