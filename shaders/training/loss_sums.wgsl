// Stage `loss_sums`: the losses' per-pixel statistics summed over strips of LOSS_STRIP pixels,
// one thread a strip, so that a step reads back 32 bytes per strip (32 KB at 256x256). Slot 0 of
// a strip holds the photometric sums (|x - y|, SSIM, (x - y)^2), slot 1 the regularisers'
// (H V, |g^t . g^r|, |M - M_a|), zero when `regularisers` did not run (its statistics then hold
// nothing of this frame: a fresh buffer's contents, or an earlier frame's).
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: LossParams;
@group(0) @binding(1) var<storage, read> stats: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> partials: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let strip = linear_index(gid, nwg, 64u);
    let pixels = params.width * params.height;
    let first = strip * LOSS_STRIP;
    if first >= pixels {
        return;
    }
    var photometric = vec4<f32>(0.0);
    var regularisers = vec4<f32>(0.0);
    for (var p = first; p < min(first + LOSS_STRIP, pixels); p++) {
        photometric += stats[2u * p];
        if params.regularisers != 0u {
            regularisers += stats[2u * p + 1u];
        }
    }
    partials[2u * strip] = photometric;
    partials[2u * strip + 1u] = regularisers;
}
