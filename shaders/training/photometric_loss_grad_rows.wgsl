// Stage `photometric_loss`, pass 3 of 4 (twin: trgs_core::reference::photometric_loss), for the
// run's colour channels: the row blur of pass 2's derivatives dL/dm_x, dL/dm_xx, dL/dm_xy (zero
// outside the image).
#include "shared/common.wgsl"
#include "shared/loss_channels.wgsl"

@group(0) @binding(0) var<storage, read> params: LossParams;
@group(0) @binding(1) var<storage, read> terms: array<f32>;
// Per pixel and channel: the three row-blurred derivatives.
@group(0) @binding(2) var<storage, read_write> rows: array<f32>;

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height {
        return;
    }
    var w = SSIM_WEIGHTS;
    var s = array<f32, LOSS_TERMS>();
    for (var t = 0u; t < 11u; t++) {
        let qx = i32(gid.x + t) - i32(SSIM_RADIUS);
        if qx < 0 || qx >= i32(params.width) {
            continue;
        }
        let j = gid.y * params.width + u32(qx);
        for (var k = 0u; k < LOSS_TERMS; k++) {
            s[k] += w[t] * terms[LOSS_TERMS * j + k];
        }
    }
    let p = gid.y * params.width + gid.x;
    for (var k = 0u; k < LOSS_TERMS; k++) {
        rows[LOSS_TERMS * p + k] = s[k];
    }
}
