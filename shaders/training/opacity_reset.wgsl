// Stage `opacity_reset` (twin: trgs_train::densify::classic::opacity_reset_logits): 3DGS's opacity
// reset in place, every opacity logit capped at `cap`, one thread per Gaussian. The opacities'
// Adam moments are cleared beside it; nothing is read back.
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: OpacityResetParams;
@group(0) @binding(1) var<storage, read_write> opacity_logits: array<f32>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = linear_index(gid, nwg, 256u);
    if i >= params.count {
        return;
    }
    // Not min(): a NaN logit must become the cap, as on the CPU, whatever min does with it.
    if !(opacity_logits[i] <= params.cap) {
        opacity_logits[i] = params.cap;
    }
}
