// Stage `prefix_sum`, join: add each block's scanned offset to its values. One workgroup per
// block of SCAN_BLOCK values (as the level scan), each thread adding the offset to SCAN_ITEMS
// of them, SCAN_THREADS apart so that a GPU's neighbouring threads touch neighbouring values:
// a CPU adapter pays per workgroup, and a block's offset is read once.
#include "shared/common.wgsl"
#include "shared/block_width.wgsl"

@group(0) @binding(0) var<storage, read> params: ScanParams;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read> block_offsets: array<u32>;

@compute @workgroup_size(SCAN_THREADS)
fn main(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    // Blocks past a GPU count are empty: `params.spread` deals the full ones out evenly.
    let block = spread_block(wid, nwg, params.spread);
    if block * SCAN_BLOCK >= params.count {
        return;
    }
    let offset = block_offsets[block];
    let base = block * SCAN_BLOCK + lid;
    for (var k = 0u; k < SCAN_ITEMS; k++) {
        let i = base + k * SCAN_THREADS;
        if i < params.count {
            data[i] += offset;
        }
    }
}
