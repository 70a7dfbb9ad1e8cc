// Stage `densify_plan`, first pass (twin: trgs_train::densify::classic::plan_densify): flag the
// Gaussians that want to densify. An exclusive scan of the flags then ranks them, so that the
// room left under max_gaussians goes to the first ones in index order, as on the CPU.
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: DensifyPlanParams;
@group(0) @binding(1) var<storage, read> stats: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> opacity_logits: array<f32>;
@group(0) @binding(3) var<storage, read_write> candidates: array<u32>;

#include "shared/densify_rules.wgsl"

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = linear_index(gid, nwg, 256u);
    if i >= params.count {
        return;
    }
    candidates[i] = select(0u, 1u, is_candidate(i));
}
