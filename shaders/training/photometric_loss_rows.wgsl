// Stage `photometric_loss`, pass 1 of 4 (twin: trgs_core::reference::photometric_loss), for one
// colour channel (`params.channel`; the four passes run once per channel, so that a scratch
// buffer holds one channel's values: 20 bytes a pixel, not 80): the row blur of SSIM's five
// moments x, y, x^2, y^2, x y with the 11-tap window; samples outside the image are zero (3DGS's
// conv2d with zero padding). One thread per pixel and no workgroup memory: lavapipe runs a
// workgroup barrier as a switch of every invocation's state, which made a shared-memory version
// several times slower than these plain passes. Both images are read multiplied by the target's
// coverage (its alpha: 0 where the photo has no source), so such a pixel is black in both and
// adds nothing.
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: LossParams;
// The frame's colour layer (C, -).
@group(0) @binding(1) var<storage, read> rendered: array<vec4<f32>>;
// The view's image, 8-bit RGBA (unpack4x8unorm; alpha: coverage).
@group(0) @binding(2) var<storage, read> target_image: array<u32>;
// Per pixel: the row-blurred x, y, x^2, y^2, x y of the channel.
@group(0) @binding(3) var<storage, read_write> rows: array<f32>;

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height {
        return;
    }
    var w = SSIM_WEIGHTS;
    var s = array<f32, 5>();
    for (var t = 0u; t < 11u; t++) {
        let qx = i32(gid.x + t) - i32(SSIM_RADIUS);
        if qx < 0 || qx >= i32(params.width) {
            continue;
        }
        let j = gid.y * params.width + u32(qx);
        let y = unpack4x8unorm(target_image[j]);
        let a = rendered[j][params.channel] * y.w;
        let b = y[params.channel] * y.w;
        s[0] += w[t] * a;
        s[1] += w[t] * b;
        s[2] += w[t] * a * a;
        s[3] += w[t] * b * b;
        s[4] += w[t] * a * b;
    }
    let p = gid.y * params.width + gid.x;
    for (var k = 0u; k < 5u; k++) {
        rows[5u * p + k] = s[k];
    }
}
