// Stage `exposure_bwd` (twin: trgs_core::reference::exposure_bwd), one thread a strip of
// LOSS_STRIP pixels: the colour gradient dL/dC' the photometric loss wrote becomes dL/dC = A^T
// dL/dC' in place, and the strip's share of dL/d(A, b) (dL/dA_ij = g'_i C_j, dL/db_i = g'_i,
// summed) goes to three vec4 per strip, row i holding [dA_i0, dA_i1, dA_i2, db_i], for the CPU to
// sum in f64 and step the view's exposure with.
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: ExposureParams;
@group(0) @binding(1) var<storage, read> rendered: array<vec4<f32>>;
// dL/d(C', -) in, dL/d(C, -) out.
@group(0) @binding(2) var<storage, read_write> grad_color: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> partials: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let strip = linear_index(gid, nwg, 64u);
    let pixels = params.width * params.height;
    let first = strip * LOSS_STRIP;
    if first >= pixels {
        return;
    }
    var d0 = vec4<f32>(0.0);
    var d1 = vec4<f32>(0.0);
    var d2 = vec4<f32>(0.0);
    for (var p = first; p < min(first + LOSS_STRIP, pixels); p++) {
        let g = grad_color[p];
        let x = vec4<f32>(rendered[p].xyz, 1.0);
        d0 += g.x * x;
        d1 += g.y * x;
        d2 += g.z * x;
        let back = g.x * params.row0 + g.y * params.row1 + g.z * params.row2;
        grad_color[p] = vec4<f32>(back.xyz, g.w);
    }
    partials[3u * strip] = d0;
    partials[3u * strip + 1u] = d1;
    partials[3u * strip + 2u] = d2;
}
