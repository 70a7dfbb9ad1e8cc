// Stage `mcmc_regularise` (twin: trgs_core::reference::mcmc_regularise): the gradients of
// 3DGS-MCMC's regularisers lambda_o mean(o) + lambda_s mean(s), added to the opacity-logit and
// log-scale gradients before the optimiser step, one thread per Gaussian (glass ones excepted).
// exp stops at MAX_REGULARISED_LOG_SCALE: a diverged scale gets a gradient whose square is
// finite in f32 (see the twin).
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: McmcParams;
@group(0) @binding(1) var<storage, read> log_scales: array<f32>;
@group(0) @binding(2) var<storage, read> opacity_logits: array<f32>;
@group(0) @binding(3) var<storage, read> populations: array<u32>;
@group(0) @binding(4) var<storage, read_write> g_log_scales: array<f32>;
@group(0) @binding(5) var<storage, read_write> g_opacity_logits: array<f32>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = linear_index(gid, nwg, 256u);
    if i >= params.count || populations[i] == POPULATION_GLASS {
        return;
    }
    let o = sigmoid(opacity_logits[i]);
    g_opacity_logits[i] += params.opacity_weight * o * (1.0 - o);
    for (var c = 0u; c < 3u; c++) {
        let s = exp(min(log_scales[3u * i + c], MAX_REGULARISED_LOG_SCALE));
        g_log_scales[3u * i + c] += params.scale_weight * s;
    }
}
