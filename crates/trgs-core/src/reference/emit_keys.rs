//! Stage `emit_keys`: one key per Gaussian and touched tile, the tile's index, with the
//! Gaussian's index as its value. Gaussians are taken in `depth_order`, each writing from its
//! offset (the exclusive prefix sum of the tile counts in that order), so the emitted list is
//! front to back and a stable sort by tile alone yields every tile's list front to back.
use super::{Projected, tile_rect};
use crate::pipeline::{TileGrid, TileRect};

/// Keys (tile indices of the whole grid) and values (Gaussian indices); `order` is the depth
/// order and `offsets[k]` the first slot of `order[k]`.
pub fn emit_keys(
    p: &Projected,
    grid: &TileGrid,
    limit: &TileRect,
    order: &[u32],
    offsets: &[u32],
    total: u32,
) -> (Vec<u32>, Vec<u32>) {
    let mut keys = vec![0u32; total as usize];
    let mut values = vec![0u32; total as usize];
    for (&i, &offset) in order.iter().zip(offsets) {
        let i = i as usize;
        let r = tile_rect(p.mean2d[i], p.extent[i], grid, limit);
        let mut slot = offset as usize;
        for ty in r.y0..r.y1 {
            for tx in r.x0..r.x1 {
                keys[slot] = ty * grid.tiles_x + tx;
                values[slot] = i as u32;
                slot += 1;
            }
        }
    }
    (keys, values)
}
