// Stage `adam` (twin: trgs_core::reference::adam): one Adam step with bias correction over a
// range of one attribute buffer, one thread per float. The moments live in buffers shaped like
// the parameters. A learning-rate pattern gives the first floats of each record their own rate.
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: AdamParams;
@group(0) @binding(1) var<storage, read_write> values: array<f32>;
@group(0) @binding(2) var<storage, read> grads: array<f32>;
@group(0) @binding(3) var<storage, read_write> m: array<f32>;
@group(0) @binding(4) var<storage, read_write> v: array<f32>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = linear_index(gid, nwg, 256u);
    if i >= params.count {
        return;
    }
    let g = grads[i];
    let mi = params.beta1 * m[i] + (1.0 - params.beta1) * g;
    let vi = params.beta2 * v[i] + (1.0 - params.beta2) * g * g;
    m[i] = mi;
    v[i] = vi;
    var lr = params.lr;
    if params.stride != 0u && (params.offset + i) % params.stride < params.lead {
        lr = params.lead_lr;
    }
    values[i] -= lr * (mi / params.bias1) / (sqrt(vi / params.bias2) + params.eps);
}
