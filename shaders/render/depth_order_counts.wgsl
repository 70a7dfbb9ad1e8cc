// Stage `depth_order` (twin: trgs_core::reference::depth_order), after its sort: the tile count
// of each entry in depth order, from the rectangle `tile_counts` kept, for `prefix_sum` to scan
// into each entry's first key slot. Slots past the last entry (`entries[0]`) are left as they
// are: the scan reads the same count.
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: ScanParams;
@group(0) @binding(1) var<storage, read> entries: array<u32>;
@group(0) @binding(2) var<storage, read> order: array<u32>;
@group(0) @binding(3) var<storage, read> rects: array<vec2<u32>>;
@group(0) @binding(4) var<storage, read_write> ordered_counts: array<u32>;

@compute @workgroup_size(256)
fn main(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    // The dispatch covers the capacity and the entries fill its first slots: spread the
    // workgroups over them (common.wgsl). DEPTH_COUNTS_BLOCK / 256 slots a thread, 256 apart:
    // a CPU adapter pays for every workgroup, empty or not (with a plane, half of them are).
    let first = spread_block(wid, nwg, params.spread) * DEPTH_COUNTS_BLOCK + lid;
    let end = min(params.count, entries[0]);
    for (var slot = first; slot < min(end, first + DEPTH_COUNTS_BLOCK); slot += 256u) {
        let r = rects[order[slot]];
        ordered_counts[slot] = ((r.y & 0xffffu) - (r.x & 0xffffu)) * ((r.y >> 16u) - (r.x >> 16u));
    }
}
