// Stage `display` (twin: trgs_core::reference::display): one layer's per-pixel vec4 to packed
// 8-bit RGBA (pack4x8unorm, red in the low byte), one row every `row_pixels` words so that the
// buffer copies straight into a texture (rows padded to 256 bytes). Modes: 0 RGB, 1 gray of one
// channel, 2 gray inverse depth between `near` and `far` (no surface: black), 3 black.
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: DisplayParams;
@group(0) @binding(1) var<storage, read> layer: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> rgba: array<u32>;

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = gid.x;
    let y = gid.y;
    if x >= params.width || y >= params.height {
        return;
    }
    let p = layer[y * params.width + x];
    var rgb = vec3<f32>(0.0);
    switch params.mode {
        case 0u: {
            rgb = p.xyz;
        }
        case 1u: {
            rgb = vec3<f32>(p[params.channel]);
        }
        case 2u: {
            let d = p[params.channel];
            var t = 0.0;
            if d > 0.0 {
                let inv_near = 1.0 / params.near;
                let inv_far = 1.0 / params.far;
                t = (1.0 / d - inv_far) / (inv_near - inv_far);
            }
            rgb = vec3<f32>(t);
        }
        default: {}
    }
    rgba[y * params.row_pixels + x] = pack4x8unorm(vec4<f32>(rgb, 1.0));
}
