// Stage `step_guard` (twin: trgs_core::reference::step_guard): whether a training step may
// change the model, decided on the GPU so that the step does not wait for its readback. The
// guard (cleared before) gets GUARD_KEYS_DROPPED when emit_keys' flag says the frame's key list
// dropped keys, and GUARD_LOSS_NOT_FINITE when a strip sum of the loss is not finite; `adam`,
// `mcmc_noise` and `densify_stats` change nothing while it is set. One thread per vec4 of sums.
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: StepGuardParams;
@group(0) @binding(1) var<storage, read> sums: array<vec4<f32>>;
// emit_keys' words: the keys kept, then whether it dropped some.
@group(0) @binding(2) var<storage, read> kept: array<u32>;
@group(0) @binding(3) var<storage, read_write> guard: array<atomic<u32>>;

// Not NaN nor infinite, by the exponent bits (a compiler may fold `v != v` away).
fn all_finite(v: vec4<f32>) -> bool {
    let exponent = bitcast<vec4<u32>>(v) & vec4<u32>(0x7f800000u);
    return all(exponent != vec4<u32>(0x7f800000u));
}

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = linear_index(gid, nwg, 256u);
    if i == 0u && kept[1] != 0u {
        atomicOr(&guard[0], GUARD_KEYS_DROPPED);
    }
    if i < params.count && !all_finite(sums[i]) {
        atomicOr(&guard[0], GUARD_LOSS_NOT_FINITE);
    }
}
