// Stage `project` (twin: trgs_core::reference::project), first kernel: the cheap culls of
// shared/project_cull.wgsl on every Gaussian. A culled Gaussian gets flags 0 here; a survivor is
// appended to `candidates`, and `work` becomes the indirect dispatch of the second kernel
// (project.wgsl) over the list: (workgroups, 1, 1, list length). `work` starts zeroed.
#include "shared/common.wgsl"
#include "shared/tiles.wgsl"
#include "shared/project_cull.wgsl"

@group(0) @binding(0) var<storage, read> view: ProjectParams;
@group(0) @binding(1) var<storage, read> means: array<f32>;
@group(0) @binding(2) var<storage, read> log_scales: array<f32>;
@group(0) @binding(3) var<storage, read> opacity_logits: array<f32>;
@group(0) @binding(4) var<storage, read> populations: array<u32>;
@group(0) @binding(5) var<storage, read_write> projected: array<ProjectedGaussian>;
@group(0) @binding(6) var<storage, read_write> candidates: array<u32>;
@group(0) @binding(7) var<storage, read_write> work: array<atomic<u32>, 4>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = linear_index(gid, nwg, 256u);
    if i == 0u {
        atomicStore(&work[1], 1u);
        atomicStore(&work[2], 1u);
    }
    if i >= view.count {
        return;
    }
    if !passes_cheap_culls(view_point(i)) {
        projected[i].flags = 0u;
        return;
    }
    let slot = atomicAdd(&work[3], 1u);
    candidates[slot] = i;
    // One more workgroup per 256 listed (a chunk has at most MAX_WORKGROUPS x 256 Gaussians).
    if slot % 256u == 0u {
        atomicAdd(&work[0], 1u);
    }
}
