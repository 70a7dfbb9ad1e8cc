// Stage `photometric_loss`, pass 3 of 4 (twin: trgs_core::reference::photometric_loss), for the
// run's colour channels: the row blur of pass 2's derivatives dL/dm_x, dL/dm_xx, dL/dm_xy (zero
// outside the image). A thread blurs a run of LOSS_BLUR_RUN pixels of a row
// (shared/loss_channels.wgsl).
#include "shared/common.wgsl"
#include "shared/loss_channels.wgsl"

@group(0) @binding(0) var<storage, read> params: LossParams;
@group(0) @binding(1) var<storage, read> terms: array<f32>;
// Per pixel and channel: the three row-blurred derivatives.
@group(0) @binding(2) var<storage, read_write> rows: array<f32>;

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    var w = SSIM_WEIGHTS;
    let first = gid.x * LOSS_BLUR_RUN;
    if first >= params.width || gid.y >= params.height {
        return;
    }
    var s = array<f32, LOSS_BLUR_RUN * LOSS_TERMS>();
    for (var i = 0u; i < LOSS_BLUR_INPUTS; i++) {
        let qx = i32(first + i) - i32(SSIM_RADIUS);
        if qx < 0 || qx >= i32(params.width) {
            continue;
        }
        let j = gid.y * params.width + u32(qx);
        var v = array<f32, LOSS_TERMS>();
        for (var k = 0u; k < LOSS_TERMS; k++) {
            v[k] = terms[LOSS_TERMS * j + k];
        }
        for (var r = 0u; r < LOSS_BLUR_RUN; r++) {
            let t = blur_tap(i, r);
            if t < SSIM_TAPS {
                let wt = w[t];
                for (var k = 0u; k < LOSS_TERMS; k++) {
                    s[LOSS_TERMS * r + k] += wt * v[k];
                }
            }
        }
    }
    for (var r = 0u; r < LOSS_BLUR_RUN; r++) {
        if first + r < params.width {
            let p = gid.y * params.width + first + r;
            for (var k = 0u; k < LOSS_TERMS; k++) {
                rows[LOSS_TERMS * p + k] = s[LOSS_TERMS * r + k];
            }
        }
    }
}
