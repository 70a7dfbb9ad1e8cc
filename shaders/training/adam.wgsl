// Stage `adam` (twin: trgs_core::reference::adam): one Adam step with bias correction over a
// range of one attribute buffer, four floats per thread as one vec4 (on a CPU adapter every
// invocation costs, and the SH buffer alone holds 48 floats a Gaussian; `bench --train-step`
// times the Adam phase). The moments live in buffers shaped like the
// parameters. A learning-rate pattern gives the first floats of each record their own rate. The
// floats of the last vec4 past the count (the buffers' padding, every binding covers whole
// vec4s) keep what they held.
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: AdamParams;
@group(0) @binding(1) var<storage, read_write> values: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> grads: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> m: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> v: array<vec4<f32>>;
// The step's `step_guard`: nothing changes while it is set.
@group(0) @binding(5) var<storage, read> guard: array<u32>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = linear_index(gid, nwg, 256u);
    let first = 4u * i;
    if first >= params.count || guard[0] != 0u {
        return;
    }
    let float_index = vec4<u32>(first) + vec4<u32>(0u, 1u, 2u, 3u);
    let live = float_index < vec4<u32>(params.count);
    let g = grads[i];
    let m0 = m[i];
    let v0 = v[i];
    let x0 = values[i];
    let mi = params.beta1 * m0 + (1.0 - params.beta1) * g;
    let vi = params.beta2 * v0 + (1.0 - params.beta2) * g * g;
    var lr = vec4<f32>(params.lr);
    if params.stride != 0u {
        let in_record = (vec4<u32>(params.offset) + float_index) % vec4<u32>(params.stride);
        lr = select(lr, vec4<f32>(params.lead_lr), in_record < vec4<u32>(params.lead));
    }
    let step = lr * (mi / params.bias1) / (sqrt(vi / params.bias2) + params.eps);
    m[i] = select(m0, mi, live);
    v[i] = select(v0, vi, live);
    values[i] = select(x0, x0 - step, live);
}
