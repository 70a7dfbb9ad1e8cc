// Stage `perturb` (twin: trgs_train::perturb::{seen_through_planes, perturb_opacities}): the
// opacity perturbation of stage 3, one thread per Gaussian. A primary Gaussian whose centre lies
// behind a plane by more than its margin, and which some training camera on the plane's front
// side sees through the plane's rectangle, gets uniform noise in [-amplitude, amplitude) on its
// opacity (numbered by its index from the seed), clamped into [clamp, 1 - clamp]. The count of
// perturbed Gaussians is summed per workgroup into `count`.
#include "shared/common.wgsl"
#include "shared/random.wgsl"

@group(0) @binding(0) var<storage, read> params: PerturbParams;
@group(0) @binding(1) var<storage, read> planes: array<PerturbPlane>;
// Camera centres (xyz).
@group(0) @binding(2) var<storage, read> cameras: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> means: array<f32>;
@group(0) @binding(4) var<storage, read> populations: array<u32>;
@group(0) @binding(5) var<storage, read_write> opacity_logits: array<f32>;
@group(0) @binding(6) var<storage, read_write> count: array<atomic<u32>>;

var<workgroup> group_count: atomic<u32>;

fn seen_through(mu: vec3<f32>) -> bool {
    for (var p = 0u; p < params.planes; p++) {
        let plane = planes[p];
        let centre = plane.centre.xyz;
        let n = plane.normal.xyz;
        // Behind the plane by more than the margin (centre.w).
        if dot(mu - centre, n) >= -plane.centre.w {
            continue;
        }
        for (var c = 0u; c < params.cameras; c++) {
            let cam = cameras[c].xyz;
            let side = dot(cam - centre, n);
            if side <= 0.0 {
                continue;
            }
            // The ray from the camera to the centre meets the plane at cam + t d.
            let d = mu - cam;
            let hit = cam + d * (-side / dot(d, n)) - centre;
            if abs(dot(hit, plane.axis.xyz)) <= plane.normal.w
                && abs(dot(hit, plane.bitangent.xyz)) <= plane.axis.w {
                return true;
            }
        }
    }
    return false;
}

@compute @workgroup_size(256)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    if lid == 0u {
        atomicStore(&group_count, 0u);
    }
    workgroupBarrier();
    let i = linear_index(gid, nwg, 256u);
    if i < params.count && populations[i] != POPULATION_GLASS {
        let mu = vec3<f32>(means[3u * i], means[3u * i + 1u], means[3u * i + 2u]);
        if seen_through(mu) {
            let u = f32(pcg_hash((params.first + i) ^ pcg_hash(params.seed)) >> 8u) / 16777216.0;
            let noisy = sigmoid(opacity_logits[i]) + params.amplitude * (2.0 * u - 1.0);
            let o = clamp(noisy, params.clamp, 1.0 - params.clamp);
            opacity_logits[i] = log(o / (1.0 - o));
            atomicAdd(&group_count, 1u);
        }
    }
    workgroupBarrier();
    if lid == 0u {
        let c = atomicLoad(&group_count);
        if c != 0u {
            atomicAdd(&count[0], c);
        }
    }
}
