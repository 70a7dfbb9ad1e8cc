// Stage `photometric_loss`, pass 4 of 4 (twin: trgs_core::reference::photometric_loss), for the
// run's colour channels: the column blur of pass 3's rows gives G*g_mx, G*g_mxx, G*g_mxy, and
// dL/dx = G*g_mx + 2 x (G*g_mxx) + y (G*g_mxy) plus the L1 term (1 - lambda) sign(x - y) /
// samples, with x and y the images times the coverage c and the result times c (zero where the
// photo has no source). It writes the run's components of the colour gradient layer (a run from
// channel 0 the whole pixel, a later one its component). A thread blurs a run of LOSS_BLUR_RUN
// pixels of a column (shared/loss_channels.wgsl).
#include "shared/common.wgsl"
#include "shared/loss_channels.wgsl"

@group(0) @binding(0) var<storage, read> params: LossParams;
@group(0) @binding(1) var<storage, read> rendered: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> target_image: array<u32>;
// Pass 3's row-blurred derivatives per pixel and channel.
@group(0) @binding(3) var<storage, read> rows: array<f32>;
// dL/d(C, -).
@group(0) @binding(4) var<storage, read_write> grad_color: array<vec4<f32>>;

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    var w = SSIM_WEIGHTS;
    let first = gid.y * LOSS_BLUR_RUN;
    if gid.x >= params.width || first >= params.height {
        return;
    }
    var b = array<f32, LOSS_BLUR_RUN * LOSS_TERMS>();
    for (var i = 0u; i < LOSS_BLUR_INPUTS; i++) {
        let qy = i32(first + i) - i32(SSIM_RADIUS);
        if qy < 0 || qy >= i32(params.height) {
            continue;
        }
        let j = u32(qy) * params.width + gid.x;
        var v = array<f32, LOSS_TERMS>();
        for (var k = 0u; k < LOSS_TERMS; k++) {
            v[k] = rows[LOSS_TERMS * j + k];
        }
        for (var r = 0u; r < LOSS_BLUR_RUN; r++) {
            let t = blur_tap(i, r);
            if t < SSIM_TAPS {
                let wt = w[t];
                for (var k = 0u; k < LOSS_TERMS; k++) {
                    b[LOSS_TERMS * r + k] += wt * v[k];
                }
            }
        }
    }
    for (var r = 0u; r < LOSS_BLUR_RUN; r++) {
        if first + r >= params.height {
            break;
        }
        let p = (first + r) * params.width + gid.x;
        let photo = unpack4x8unorm(target_image[p]);
        let c = photo.w;
        let colour = rendered[p];
        var out = vec4<f32>(0.0);
        if params.channel != 0u {
            out = grad_color[p];
        }
        for (var k = 0u; k < LOSS_CHANNELS; k++) {
            let o = LOSS_TERMS * r + 3u * k;
            let x = colour[loss_channel(k)] * c;
            let y = photo[loss_channel(k)] * c;
            let l1 = (1.0 - params.lambda_dssim) * sign(x - y) * params.inv_samples;
            out[loss_channel(k)] = c * (l1 + b[o] + 2.0 * x * b[o + 1u] + y * b[o + 2u]);
        }
        grad_color[p] = out;
    }
}
