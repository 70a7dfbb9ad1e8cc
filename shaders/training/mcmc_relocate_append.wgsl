// Stage `mcmc_relocate`, last pass (twin: plan_relocation), one thread per growth draw: row
// count + j becomes a copy of the j-th drawn row (after its share), with restarting moments.
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: McmcRelocateParams;
// The growth's weight total in the first word: nothing is added when it is zero.
@group(0) @binding(1) var<storage, read> total: array<u32>;
@group(0) @binding(2) var<storage, read> draws: array<u32>;
@group(0) @binding(3) var<storage, read_write> new_opacity_logits: array<f32>;
@group(0) @binding(4) var<storage, read_write> new_log_scales: array<f32>;
@group(0) @binding(5) var<storage, read_write> sources: array<u32>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let j = linear_index(gid, nwg, 256u);
    if j >= params.growth || total[0] == 0u {
        return;
    }
    let s = draws[j];
    let row = params.count + j;
    new_opacity_logits[row] = new_opacity_logits[s];
    for (var c = 0u; c < 3u; c++) {
        new_log_scales[3u * row + c] = new_log_scales[3u * s + c];
    }
    sources[row] = sources[s] | GATHER_ZERO;
}
