// Stage `mcmc_noise` (twin: trgs_core::reference::mcmc_noise): 3DGS-MCMC's exploration term,
// added to every primary Gaussian's mean after the optimiser step, one thread per Gaussian:
// Sigma eta sigmoid(k (1 - o - t)) scale. Nearly transparent Gaussians wander; opaque ones stay.
#include "shared/common.wgsl"
#include "shared/random.wgsl"

@group(0) @binding(0) var<storage, read> params: McmcParams;
@group(0) @binding(1) var<storage, read_write> means: array<f32>;
@group(0) @binding(2) var<storage, read> rotations: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> log_scales: array<f32>;
@group(0) @binding(4) var<storage, read> opacity_logits: array<f32>;
@group(0) @binding(5) var<storage, read> populations: array<u32>;
// The step's `step_guard`: nothing moves while it is set.
@group(0) @binding(6) var<storage, read> guard: array<u32>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = linear_index(gid, nwg, 256u);
    if i >= params.count || populations[i] == POPULATION_GLASS || guard[0] != 0u {
        return;
    }
    let o = sigmoid(opacity_logits[i]);
    let gate = sigmoid(NOISE_GATE_STEEPNESS * (1.0 - o - NOISE_GATE_THRESHOLD));
    let r = quat_to_mat(rotations[i]);
    let s = exp(vec3<f32>(log_scales[3u * i], log_scales[3u * i + 1u], log_scales[3u * i + 2u]));
    let l = mat3x3<f32>(r[0] * s.x, r[1] * s.y, r[2] * s.z);
    let k = params.first + i;
    let eta = vec3<f32>(
        noise_normal(params.seed, k, 0u),
        noise_normal(params.seed, k, 1u),
        noise_normal(params.seed, k, 2u),
    );
    let d = (l * (transpose(l) * eta)) * (gate * params.noise_scale);
    means[3u * i] += d.x;
    means[3u * i + 1u] += d.y;
    means[3u * i + 2u] += d.z;
}
