// Not a stage: a check kernel for the test that compares `spread_block` (shared/common.wgsl)
// with its twin `trgs_render::gpu::spread_block` on every grid shape a 1D dispatch can take.
// Each workgroup writes the block it takes at its own linear index.
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: ScanParams;
@group(0) @binding(1) var<storage, read_write> blocks: array<u32>;

@compute @workgroup_size(1)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    blocks[wid.x + wid.y * nwg.x] = spread_block(wid, nwg, params.spread);
}
