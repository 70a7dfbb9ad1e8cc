// Stage `photometric_loss`, pass 3 of 4 (twin: trgs_core::reference::photometric_loss), for one
// colour channel: the row blur of pass 2's derivatives dL/dm_x, dL/dm_xx, dL/dm_xy (zero outside
// the image).
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: LossParams;
@group(0) @binding(1) var<storage, read> terms: array<f32>;
// Per pixel: the three row-blurred derivatives.
@group(0) @binding(2) var<storage, read_write> rows: array<f32>;

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height {
        return;
    }
    var w = SSIM_WEIGHTS;
    var s = array<f32, 3>();
    for (var t = 0u; t < 11u; t++) {
        let qx = i32(gid.x + t) - i32(SSIM_RADIUS);
        if qx < 0 || qx >= i32(params.width) {
            continue;
        }
        let j = gid.y * params.width + u32(qx);
        for (var k = 0u; k < 3u; k++) {
            s[k] += w[t] * terms[3u * j + k];
        }
    }
    let p = gid.y * params.width + gid.x;
    for (var k = 0u; k < 3u; k++) {
        rows[3u * p + k] = s[k];
    }
}
