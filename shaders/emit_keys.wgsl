// Stage `emit_keys` (twin: trgs_core::reference::emit_keys): one (tile, depth) key per Gaussian
// and touched tile, written from the Gaussian's offset (the exclusive prefix sum of the counts)
// after the view's `key_base`: every view of a frame writes into one list, sorted once. The
// 64-bit key is split in two words: `keys_hi` the tile index, numbered from the view's
// `tile_base` row by row within its tile limit, `keys_lo` the f32 bits of the (positive) depth,
// which sort like the numbers. One thread per Gaussian of project's candidate list (dispatched
// indirectly): no other Gaussian is visible.
#include "shared/common.wgsl"
#include "shared/tiles.wgsl"

@group(0) @binding(0) var<storage, read> tiles: TileParams;
@group(0) @binding(1) var<storage, read> projected: array<ProjectedGaussian>;
@group(0) @binding(2) var<storage, read> offsets: array<u32>;
@group(0) @binding(3) var<storage, read_write> keys_hi: array<u32>;
@group(0) @binding(4) var<storage, read_write> keys_lo: array<u32>;
@group(0) @binding(5) var<storage, read_write> values: array<u32>;
@group(0) @binding(6) var<storage, read> candidates: array<u32>;
@group(0) @binding(7) var<storage, read> work: array<u32, 4>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= work[3] {
        return;
    }
    let i = candidates[gid.x];
    let g = projected[i];
    if !is_visible(g) {
        return;
    }
    let r = tile_rect(g, tiles);
    let depth_bits = bitcast<u32>(g.color.w);
    var slot = tiles.key_base + offsets[i];
    let row = tiles.limit.z - tiles.limit.x;
    for (var ty = r.y; ty < r.w; ty++) {
        for (var tx = r.x; tx < r.z; tx++) {
            keys_hi[slot] = tiles.tile_base + (ty - tiles.limit.y) * row + (tx - tiles.limit.x);
            keys_lo[slot] = depth_bits;
            values[slot] = tiles.first + i;
            slot++;
        }
    }
}
