// Stage `exposure` (twin: trgs_core::reference::exposure): the training view's affine colour map
// C' = A C + b applied to every rendered pixel, for the photometric loss to compare with the
// photo. The fourth component passes through.
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: ExposureParams;
@group(0) @binding(1) var<storage, read> rendered: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> exposed: array<vec4<f32>>;

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height {
        return;
    }
    let p = gid.y * params.width + gid.x;
    let c = rendered[p];
    let x = vec4<f32>(c.xyz, 1.0);
    exposed[p] = vec4<f32>(dot(params.row0, x), dot(params.row1, x), dot(params.row2, x), c.w);
}
