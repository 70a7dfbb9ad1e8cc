// Stage `photometric_loss`, pass 4 of 4 (twin: trgs_core::reference::photometric_loss), for the
// run's colour channels: the column blur of pass 3's rows gives G*g_mx, G*g_mxx, G*g_mxy, and
// dL/dx = G*g_mx + 2 x (G*g_mxx) + y (G*g_mxy) plus the L1 term (1 - lambda) sign(x - y) /
// samples, with x and y the images times the coverage c and the result times c (zero where the
// photo has no source). It writes the run's components of the colour gradient layer (a run from
// channel 0 the whole pixel, a later one its component).
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
    if gid.x >= params.width || gid.y >= params.height {
        return;
    }
    var w = SSIM_WEIGHTS;
    var b = array<f32, LOSS_TERMS>();
    for (var t = 0u; t < 11u; t++) {
        let qy = i32(gid.y + t) - i32(SSIM_RADIUS);
        if qy < 0 || qy >= i32(params.height) {
            continue;
        }
        let j = u32(qy) * params.width + gid.x;
        for (var k = 0u; k < LOSS_TERMS; k++) {
            b[k] += w[t] * rows[LOSS_TERMS * j + k];
        }
    }
    let p = gid.y * params.width + gid.x;
    let photo = unpack4x8unorm(target_image[p]);
    let c = photo.w;
    let colour = rendered[p];
    var out = vec4<f32>(0.0);
    if params.channel != 0u {
        out = grad_color[p];
    }
    for (var k = 0u; k < LOSS_CHANNELS; k++) {
        let x = colour[loss_channel(k)] * c;
        let y = photo[loss_channel(k)] * c;
        let l1 = (1.0 - params.lambda_dssim) * sign(x - y) * params.inv_samples;
        out[loss_channel(k)] =
            c * (l1 + b[3u * k] + 2.0 * x * b[3u * k + 1u] + y * b[3u * k + 2u]);
    }
    grad_color[p] = out;
}
