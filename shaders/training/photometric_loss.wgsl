// Stage `photometric_loss`, pass 2 of 4 (twin: trgs_core::reference::photometric_loss), for the
// run's colour channels: the column blur of pass 1's rows gives the five moments; from them SSIM
// and its derivatives with respect to the blurred moments m_x, m_xx, m_xy, already scaled by
// dL/dSSIM = -lambda / samples, for passes 3 and 4 to blur back (the zero-padded window is its
// own adjoint). Also each pixel's |x - y|, SSIM and (x - y)^2, summed over the channels (a run
// from channel 0 writes, a later one adds), for `loss_sums`. A thread blurs a run of
// LOSS_BLUR_RUN pixels of a column (shared/loss_channels.wgsl).
#include "shared/common.wgsl"
#include "shared/loss_channels.wgsl"

@group(0) @binding(0) var<storage, read> params: LossParams;
@group(0) @binding(1) var<storage, read> rendered: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> target_image: array<u32>;
// Pass 1's five row-blurred moments per pixel and channel.
@group(0) @binding(3) var<storage, read> rows: array<f32>;
// Per pixel and channel: dL/dm_x, dL/dm_xx, dL/dm_xy.
@group(0) @binding(4) var<storage, read_write> terms: array<f32>;
// Per pixel: (|x - y|, SSIM, (x - y)^2, 0) summed over channels; regularisers at 2 p + 1.
@group(0) @binding(5) var<storage, read_write> stats: array<vec4<f32>>;

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    var w = SSIM_WEIGHTS;
    let first = gid.y * LOSS_BLUR_RUN;
    if gid.x >= params.width || first >= params.height {
        return;
    }
    var m = array<f32, LOSS_BLUR_RUN * LOSS_MOMENTS>();
    for (var i = 0u; i < LOSS_BLUR_INPUTS; i++) {
        let qy = i32(first + i) - i32(SSIM_RADIUS);
        if qy < 0 || qy >= i32(params.height) {
            continue;
        }
        let j = u32(qy) * params.width + gid.x;
        var v = array<f32, LOSS_MOMENTS>();
        for (var k = 0u; k < LOSS_MOMENTS; k++) {
            v[k] = rows[LOSS_MOMENTS * j + k];
        }
        for (var r = 0u; r < LOSS_BLUR_RUN; r++) {
            let t = blur_tap(i, r);
            if t < SSIM_TAPS {
                let wt = w[t];
                for (var k = 0u; k < LOSS_MOMENTS; k++) {
                    m[LOSS_MOMENTS * r + k] += wt * v[k];
                }
            }
        }
    }
    let g_s = -params.lambda_dssim * params.inv_samples;
    for (var r = 0u; r < LOSS_BLUR_RUN; r++) {
        if first + r >= params.height {
            break;
        }
        let p = (first + r) * params.width + gid.x;
        let photo = unpack4x8unorm(target_image[p]);
        let colour = rendered[p];
        var here = vec4<f32>(0.0);
        for (var c = 0u; c < LOSS_CHANNELS; c++) {
            let o = LOSS_MOMENTS * r + 5u * c;
            let mx = m[o];
            let my = m[o + 1u];
            let a1 = 2.0 * mx * my + SSIM_C1;
            let a2 = 2.0 * (m[o + 4u] - mx * my) + SSIM_C2;
            let b1 = mx * mx + my * my + SSIM_C1;
            let b2 = (m[o + 2u] - mx * mx) + (m[o + 3u] - my * my) + SSIM_C2;
            let s = a1 * a2 / (b1 * b2);
            // S/A1 = A2/(B1 B2) and S/A2 = A1/(B1 B2), as in the twin: A2 can be exactly zero.
            let inv_b = 1.0 / (b1 * b2);
            let g_mx = g_s * (2.0 * my * (a2 - a1) * inv_b - 2.0 * mx * s / b1 + 2.0 * mx * s / b2);
            terms[LOSS_TERMS * p + 3u * c] = g_mx;
            terms[LOSS_TERMS * p + 3u * c + 1u] = -g_s * s / b2;
            terms[LOSS_TERMS * p + 3u * c + 2u] = g_s * 2.0 * a1 * inv_b;
            let d = (colour[loss_channel(c)] - photo[loss_channel(c)]) * photo.w;
            here += vec4<f32>(abs(d), s, d * d, 0.0);
        }
        if params.channel == 0u {
            stats[2u * p] = here;
        } else {
            stats[2u * p] += here;
        }
    }
}
