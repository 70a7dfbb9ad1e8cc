// Stage `photometric_loss`, pass 2 of 2 (twin: trgs_core::reference::photometric_loss): dL/dC of
// the photometric loss. It blurs pass 1's derivatives with respect to the blurred moments back to
// the pixels, dL/dx = G*g_mx + 2 x (G*g_mxx) + y (G*g_mxy), and adds the L1 term
// (1 - lambda) sign(x - y) / samples. It writes (overwrites) the colour gradient layer.
#include "shared/common.wgsl"
#include "shared/loss_block.wgsl"

@group(0) @binding(0) var<storage, read> params: LossParams;
@group(0) @binding(1) var<storage, read> rendered: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> target_image: array<u32>;
// Pass 1's dL/dm_x, dL/dm_xx, dL/dm_xy per pixel.
@group(0) @binding(3) var<storage, read> terms: array<vec4<f32>>;
// dL/d(C, -).
@group(0) @binding(4) var<storage, read_write> grad_color: array<vec4<f32>>;

var<workgroup> span_mx: array<f32, LOSS_SPAN_SAMPLES>;
var<workgroup> span_mxx: array<f32, LOSS_SPAN_SAMPLES>;
var<workgroup> span_mxy: array<f32, LOSS_SPAN_SAMPLES>;
// Row-blurred g_mx, g_mxx, g_mxy, one LOSS_ROW_SAMPLES block each.
var<workgroup> rows: array<f32, 1248>;

@compute @workgroup_size(16, 16)
fn main(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_id) lid: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    let origin = wg.xy * LOSS_BLOCK;
    let px = origin + lid.xy;
    let inside = px.x < params.width && px.y < params.height;
    let p = px.y * params.width + px.x;
    var w = SSIM_WEIGHTS;
    var x = vec4<f32>(0.0);
    var y = vec4<f32>(0.0);
    if inside {
        x = rendered[p];
        y = unpack4x8unorm(target_image[p]);
    }
    var grad = vec4<f32>(0.0);
    for (var c = 0u; c < 3u; c++) {
        for (var k = li; k < LOSS_SPAN_SAMPLES; k += 256u) {
            let q = loss_span_pixel(origin, k, params.width, params.height);
            var t = vec3<f32>(0.0);
            if q.z == 1u {
                let j = q.y * params.width + q.x;
                t = vec3<f32>(terms[3u * j][c], terms[3u * j + 1u][c], terms[3u * j + 2u][c]);
            }
            span_mx[k] = t.x;
            span_mxx[k] = t.y;
            span_mxy[k] = t.z;
        }
        workgroupBarrier();
        for (var k = li; k < LOSS_ROW_SAMPLES; k += 256u) {
            let first = (k / LOSS_BLOCK) * LOSS_SPAN + k % LOSS_BLOCK;
            var s = vec3<f32>(0.0);
            for (var t = 0u; t < 11u; t++) {
                let j = first + t;
                s += w[t] * vec3<f32>(span_mx[j], span_mxx[j], span_mxy[j]);
            }
            rows[k] = s.x;
            rows[LOSS_ROW_SAMPLES + k] = s.y;
            rows[2u * LOSS_ROW_SAMPLES + k] = s.z;
        }
        workgroupBarrier();
        var b = vec3<f32>(0.0);
        for (var t = 0u; t < 11u; t++) {
            let k = (lid.y + t) * LOSS_BLOCK + lid.x;
            b += w[t] * vec3<f32>(
                rows[k],
                rows[LOSS_ROW_SAMPLES + k],
                rows[2u * LOSS_ROW_SAMPLES + k],
            );
        }
        let l1 = (1.0 - params.lambda_dssim) * sign(x[c] - y[c]) * params.inv_samples;
        grad[c] = l1 + b.x + 2.0 * x[c] * b.y + y[c] * b.z;
        // The next channel overwrites the spans and rows.
        workgroupBarrier();
    }
    if inside {
        grad_color[p] = grad;
    }
}
