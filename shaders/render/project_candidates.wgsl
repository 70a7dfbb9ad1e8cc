// Stage `project` (twin: trgs_core::reference::project), first kernel: the cheap culls of
// shared/project_cull.wgsl on every Gaussian, for up to CULL_VIEWS views at once (the camera and
// the mirrored views of a frame, `views` holds as many parameter blocks as there are). Each
// Gaussian is read and its view-independent terms computed once, then tested in every view. In
// view k, a culled Gaussian gets flags 0 in `projected_k`; a survivor is appended to `list_k`,
// and `work_k` becomes the indirect dispatch of the second kernel (project.wgsl) over the list:
// (workgroups, 1, 1, list length). The `work_k` start zeroed; the bindings of views past the
// group's last are never touched.
#include "shared/common.wgsl"
#include "shared/tiles.wgsl"
#include "shared/project_cull.wgsl"

@group(0) @binding(0) var<storage, read> views: array<ProjectParams>;
@group(0) @binding(1) var<storage, read> means: array<f32>;
@group(0) @binding(2) var<storage, read> log_scales: array<f32>;
@group(0) @binding(3) var<storage, read> opacity_logits: array<f32>;
@group(0) @binding(4) var<storage, read> populations: array<u32>;
@group(0) @binding(5) var<storage, read_write> projected_0: array<ProjectedGaussian>;
@group(0) @binding(6) var<storage, read_write> list_0: array<u32>;
@group(0) @binding(7) var<storage, read_write> work_0: array<atomic<u32>, 4>;
@group(0) @binding(8) var<storage, read_write> projected_1: array<ProjectedGaussian>;
@group(0) @binding(9) var<storage, read_write> list_1: array<u32>;
@group(0) @binding(10) var<storage, read_write> work_1: array<atomic<u32>, 4>;
@group(0) @binding(11) var<storage, read_write> projected_2: array<ProjectedGaussian>;
@group(0) @binding(12) var<storage, read_write> list_2: array<u32>;
@group(0) @binding(13) var<storage, read_write> work_2: array<atomic<u32>, 4>;

// (Storage pointers cannot be function arguments in WGSL: each view's bindings are named.)
@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = linear_index(gid, nwg, 256u);
    let n = arrayLength(&views);
    if i == 0u {
        atomicStore(&work_0[1], 1u);
        atomicStore(&work_0[2], 1u);
        if n > 1u {
            atomicStore(&work_1[1], 1u);
            atomicStore(&work_1[2], 1u);
        }
        if n > 2u {
            atomicStore(&work_2[1], 1u);
            atomicStore(&work_2[2], 1u);
        }
    }
    if i >= views[0].count {
        return;
    }
    let g = gaussian_point(i);
    // One more workgroup per 256 listed (a chunk has at most MAX_WORKGROUPS x 256 Gaussians).
    if passes_cheap_culls(views[0], in_view(views[0], g)) {
        let slot = atomicAdd(&work_0[3], 1u);
        list_0[slot] = i;
        if slot % 256u == 0u {
            atomicAdd(&work_0[0], 1u);
        }
    } else {
        projected_0[i].flags = 0u;
    }
    if n > 1u {
        if passes_cheap_culls(views[1], in_view(views[1], g)) {
            let slot = atomicAdd(&work_1[3], 1u);
            list_1[slot] = i;
            if slot % 256u == 0u {
                atomicAdd(&work_1[0], 1u);
            }
        } else {
            projected_1[i].flags = 0u;
        }
    }
    if n > 2u {
        if passes_cheap_culls(views[2], in_view(views[2], g)) {
            let slot = atomicAdd(&work_2[3], 1u);
            list_2[slot] = i;
            if slot % 256u == 0u {
                atomicAdd(&work_2[0], 1u);
            }
        } else {
            projected_2[i].flags = 0u;
        }
    }
}
