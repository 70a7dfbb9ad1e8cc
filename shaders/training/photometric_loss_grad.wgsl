// Stage `photometric_loss`, pass 4 of 4 (twin: trgs_core::reference::photometric_loss), for one
// colour channel: the column blur of pass 3's rows gives G*g_mx, G*g_mxx, G*g_mxy, and dL/dx =
// G*g_mx + 2 x (G*g_mxx) + y (G*g_mxy) plus the L1 term (1 - lambda) sign(x - y) / samples, with
// x and y the images times the coverage c and the result times c (zero where the photo has no
// source). It writes the channel's component of the colour gradient layer (the first channel
// the whole pixel, the others add their component).
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: LossParams;
@group(0) @binding(1) var<storage, read> rendered: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> target_image: array<u32>;
// Pass 3's row-blurred derivatives per pixel.
@group(0) @binding(3) var<storage, read> rows: array<f32>;
// dL/d(C, -).
@group(0) @binding(4) var<storage, read_write> grad_color: array<vec4<f32>>;

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height {
        return;
    }
    var w = SSIM_WEIGHTS;
    var b = array<f32, 3>();
    for (var t = 0u; t < 11u; t++) {
        let qy = i32(gid.y + t) - i32(SSIM_RADIUS);
        if qy < 0 || qy >= i32(params.height) {
            continue;
        }
        let j = u32(qy) * params.width + gid.x;
        for (var k = 0u; k < 3u; k++) {
            b[k] += w[t] * rows[3u * j + k];
        }
    }
    let p = gid.y * params.width + gid.x;
    let photo = unpack4x8unorm(target_image[p]);
    let c = photo.w;
    let x = rendered[p][params.channel] * c;
    let y = photo[params.channel] * c;
    let l1 = (1.0 - params.lambda_dssim) * sign(x - y) * params.inv_samples;
    let g = c * (l1 + b[0] + 2.0 * x * b[1] + y * b[2]);
    var out = vec4<f32>(0.0);
    if params.channel != 0u {
        out = grad_color[p];
    }
    out[params.channel] = g;
    grad_color[p] = out;
}
