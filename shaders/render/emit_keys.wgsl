// Stage `emit_keys` (twin: trgs_core::reference::emit_keys): one key per entry and touched tile,
// the tile's index in the key list that every view shares (a view's tiles numbered from its
// `tile_base`, row by row within its limit), with the Gaussian's index as the value. One thread
// per entry of the depth order, over every view at once, writing from the entry's offset (the
// exclusive scan of the counts in that order): the list comes out front to back, so `sort`
// orders it by tile alone and every tile's list stays front to back. A key list sized from
// earlier frames holds `params.capacity` pairs: the keys past it are dropped, and the frame
// reports that it outgrew the list (`Frame::settle_keys`).
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: EmitParams;
@group(0) @binding(1) var<storage, read> order: array<u32>;
@group(0) @binding(2) var<storage, read> rects: array<vec2<u32>>;
@group(0) @binding(3) var<storage, read> offsets: array<u32>;
@group(0) @binding(4) var<storage, read> views: array<ViewTiles>;
@group(0) @binding(5) var<storage, read_write> keys: array<u32>;
@group(0) @binding(6) var<storage, read_write> values: array<u32>;
// The scan's total of every view's keys, and where the keys the list holds are counted:
// min(total, params.capacity), the count `sort` and `tile_ranges` then cover, then whether the
// list dropped keys (1) or held them all (0), which a training step's `step_guard` reads.
@group(0) @binding(7) var<storage, read> total: array<u32>;
@group(0) @binding(8) var<storage, read_write> kept: array<u32>;
#ifdef PAGED
// The pairs from index params.page on (a key list of two pages, toolkit::paged).
@group(0) @binding(9) var<storage, read_write> keys_hi: array<u32>;
@group(0) @binding(10) var<storage, read_write> values_hi: array<u32>;

fn write_pair(i: u32, key: u32, value: u32) {
    if i >= params.capacity {
        return;
    }
    if i < params.page {
        keys[i] = key;
        values[i] = value;
    } else {
        keys_hi[i - params.page] = key;
        values_hi[i - params.page] = value;
    }
}
#else
fn write_pair(i: u32, key: u32, value: u32) {
    if i >= params.capacity {
        return;
    }
    keys[i] = key;
    values[i] = value;
}
#endif

@compute @workgroup_size(256)
fn main(
    @builtin(local_invocation_id) lid: vec3<u32>,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let first = strided_first(wid, nwg);
    if first == 0u && lid.x == 0u {
        kept[0] = min(total[0], params.capacity);
        kept[1] = select(0u, 1u, total[0] > params.capacity);
    }
    // Strided over the entries' blocks: with the entries counted on the GPU only, no workgroup
    // passes over the empty blocks of their capacity.
    let blocks = blocks_of(params.entries, 256u);
    for (var block = first; block < blocks; block += strided_step(nwg)) {
        let k = block * 256u + lid.x;
        if k < params.entries {
            emit_entry(k);
        }
    }
}

// The keys of the depth order's entry `k`.
fn emit_entry(k: u32) {
    let entry = order[k];
    let view = entry / params.gaussians;
    let gaussian = entry - view * params.gaussians;
    let packed = rects[entry];
    let x0 = packed.x & 0xffffu;
    let y0 = packed.x >> 16u;
    let x1 = packed.y & 0xffffu;
    let y1 = packed.y >> 16u;
    let t = views[view];
    var slot = offsets[k];
    for (var ty = y0; ty < y1; ty++) {
        for (var tx = x0; tx < x1; tx++) {
            write_pair(slot, t.tile_base + (ty - t.y0) * t.row + (tx - t.x0), gaussian);
            slot++;
        }
    }
}
