// Stage `prefix_sum`, join: add each block's scanned offset to its values.
#include "shared/common.wgsl"
#include "shared/block_width.wgsl"

@group(0) @binding(0) var<storage, read> params: ScanParams;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read> block_offsets: array<u32>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = linear_index(gid, nwg, 256u);
    if i >= params.count {
        return;
    }
    data[i] += block_offsets[i / SCAN_BLOCK];
}
