// Stage `photometric_loss`, pass 1 of 4 (twin: trgs_core::reference::photometric_loss), for the
// run's colour channels (shared/loss_channels.wgsl): the row blur of SSIM's five moments x, y,
// x^2, y^2, x y with the 11-tap window; samples outside the image are zero (3DGS's conv2d with
// zero padding). One thread per pixel and no workgroup memory: lavapipe runs a workgroup barrier
// as a switch of every invocation's state, which made a shared-memory version several times
// slower than these plain passes. Both images are read multiplied by the target's coverage (its
// alpha: 0 where the photo has no source), so such a pixel is black in both and adds nothing.
#include "shared/common.wgsl"
#include "shared/loss_channels.wgsl"

@group(0) @binding(0) var<storage, read> params: LossParams;
// The frame's colour layer (C, -).
@group(0) @binding(1) var<storage, read> rendered: array<vec4<f32>>;
// The view's image, 8-bit RGBA (unpack4x8unorm; alpha: coverage).
@group(0) @binding(2) var<storage, read> target_image: array<u32>;
// Per pixel and channel: the row-blurred x, y, x^2, y^2, x y.
@group(0) @binding(3) var<storage, read_write> rows: array<f32>;

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height {
        return;
    }
    var w = SSIM_WEIGHTS;
    var s = array<f32, LOSS_MOMENTS>();
    for (var t = 0u; t < 11u; t++) {
        let qx = i32(gid.x + t) - i32(SSIM_RADIUS);
        if qx < 0 || qx >= i32(params.width) {
            continue;
        }
        let j = gid.y * params.width + u32(qx);
        let y = unpack4x8unorm(target_image[j]);
        let x = rendered[j];
        for (var c = 0u; c < LOSS_CHANNELS; c++) {
            let a = x[loss_channel(c)] * y.w;
            let b = y[loss_channel(c)] * y.w;
            s[5u * c] += w[t] * a;
            s[5u * c + 1u] += w[t] * b;
            s[5u * c + 2u] += w[t] * a * a;
            s[5u * c + 3u] += w[t] * b * b;
            s[5u * c + 4u] += w[t] * a * b;
        }
    }
    let p = gid.y * params.width + gid.x;
    for (var k = 0u; k < LOSS_MOMENTS; k++) {
        rows[LOSS_MOMENTS * p + k] = s[k];
    }
}
