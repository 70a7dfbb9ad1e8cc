// Stage `photometric_loss`, pass 1 of 2 (twin: trgs_core::reference::photometric_loss): the
// per-pixel terms of 3DGS's (1 - lambda) L1 + lambda (1 - SSIM) between the rendered image and
// the view's target. For every channel it blurs the five moments (x, y, x^2, y^2, x y) with the
// SSIM window, evaluates SSIM, and writes its derivatives with respect to the blurred moments
// m_x, m_xx, m_xy, already scaled by dL/dSSIM = -lambda / samples. Pass 2
// (`photometric_loss_grad`) blurs them back (the zero-padded window is its own adjoint) and adds
// the L1 term. Each workgroup also writes its sums of |x - y|, SSIM and (x - y)^2.
#include "shared/common.wgsl"
#include "shared/loss_block.wgsl"

@group(0) @binding(0) var<storage, read> params: LossParams;
// The frame's colour layer (C, 0).
@group(0) @binding(1) var<storage, read> rendered: array<vec4<f32>>;
// The view's image, 8-bit RGBA (unpack4x8unorm).
@group(0) @binding(2) var<storage, read> target_image: array<u32>;
// Per pixel: dL/dm_x, dL/dm_xx, dL/dm_xy (RGB, 0).
@group(0) @binding(3) var<storage, read_write> terms: array<vec4<f32>>;
// Per workgroup: (sum |x - y|, sum SSIM, sum (x - y)^2, 0) over its pixels and channels.
@group(0) @binding(4) var<storage, read_write> partials: array<vec4<f32>>;

var<workgroup> span_x: array<f32, LOSS_SPAN_SAMPLES>;
var<workgroup> span_y: array<f32, LOSS_SPAN_SAMPLES>;
// Row-blurred x, y, x^2, y^2, x y, one LOSS_ROW_SAMPLES block each.
var<workgroup> rows: array<f32, 2080>;

@compute @workgroup_size(16, 16)
fn main(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_id) lid: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    let origin = wg.xy * LOSS_BLOCK;
    let px = origin + lid.xy;
    let inside = px.x < params.width && px.y < params.height;
    let p = px.y * params.width + px.x;
    var w = SSIM_WEIGHTS;
    let g_s = -params.lambda_dssim * params.inv_samples;
    var g_mx = vec4<f32>(0.0);
    var g_mxx = vec4<f32>(0.0);
    var g_mxy = vec4<f32>(0.0);
    var ssim_sum = 0.0;
    for (var c = 0u; c < 3u; c++) {
        for (var k = li; k < LOSS_SPAN_SAMPLES; k += 256u) {
            let q = loss_span_pixel(origin, k, params.width, params.height);
            var a = 0.0;
            var b = 0.0;
            if q.z == 1u {
                let j = q.y * params.width + q.x;
                a = rendered[j][c];
                b = unpack4x8unorm(target_image[j])[c];
            }
            span_x[k] = a;
            span_y[k] = b;
        }
        workgroupBarrier();
        for (var k = li; k < LOSS_ROW_SAMPLES; k += 256u) {
            let first = (k / LOSS_BLOCK) * LOSS_SPAN + k % LOSS_BLOCK;
            var s = vec4<f32>(0.0);
            var s_xy = 0.0;
            for (var t = 0u; t < 11u; t++) {
                let a = span_x[first + t];
                let b = span_y[first + t];
                s += w[t] * vec4<f32>(a, b, a * a, b * b);
                s_xy += w[t] * a * b;
            }
            rows[k] = s.x;
            rows[LOSS_ROW_SAMPLES + k] = s.y;
            rows[2u * LOSS_ROW_SAMPLES + k] = s.z;
            rows[3u * LOSS_ROW_SAMPLES + k] = s.w;
            rows[4u * LOSS_ROW_SAMPLES + k] = s_xy;
        }
        workgroupBarrier();
        var m = vec4<f32>(0.0);
        var m_xy = 0.0;
        for (var t = 0u; t < 11u; t++) {
            let k = (lid.y + t) * LOSS_BLOCK + lid.x;
            m += w[t] * vec4<f32>(
                rows[k],
                rows[LOSS_ROW_SAMPLES + k],
                rows[2u * LOSS_ROW_SAMPLES + k],
                rows[3u * LOSS_ROW_SAMPLES + k],
            );
            m_xy += w[t] * rows[4u * LOSS_ROW_SAMPLES + k];
        }
        if inside {
            let mx = m.x;
            let my = m.y;
            let a1 = 2.0 * mx * my + SSIM_C1;
            let a2 = 2.0 * (m_xy - mx * my) + SSIM_C2;
            let b1 = mx * mx + my * my + SSIM_C1;
            let b2 = (m.z - mx * mx) + (m.w - my * my) + SSIM_C2;
            let s = a1 * a2 / (b1 * b2);
            ssim_sum += s;
            g_mx[c] = g_s * s * (2.0 * my / a1 - 2.0 * my / a2 - 2.0 * mx / b1 + 2.0 * mx / b2);
            g_mxx[c] = -g_s * s / b2;
            g_mxy[c] = g_s * s * 2.0 / a2;
        }
        // The next channel overwrites the spans and rows.
        workgroupBarrier();
    }
    var l1 = 0.0;
    var sq = 0.0;
    if inside {
        terms[3u * p] = g_mx;
        terms[3u * p + 1u] = g_mxx;
        terms[3u * p + 2u] = g_mxy;
        let d = rendered[p].xyz - unpack4x8unorm(target_image[p]).xyz;
        l1 = abs(d.x) + abs(d.y) + abs(d.z);
        sq = dot(d, d);
    }
    // Workgroup sums, reusing the spans and the first row block as scratch.
    span_x[li] = l1;
    span_y[li] = ssim_sum;
    rows[li] = sq;
    workgroupBarrier();
    for (var stride = 128u; stride > 0u; stride >>= 1u) {
        if li < stride {
            span_x[li] += span_x[li + stride];
            span_y[li] += span_y[li + stride];
            rows[li] += rows[li + stride];
        }
        workgroupBarrier();
    }
    if li == 0u {
        partials[wg.y * nwg.x + wg.x] = vec4<f32>(span_x[0], span_y[0], rows[0], 0.0);
    }
}
