// Stage `compose` (twin: trgs_core::reference::compose): per pixel, the nearest plane whose
// rectangle the camera ray hits from the front side (hit mask H = k + 1), Schlick's
// R_raw = R0 + (1 - R0) (1 - cos)^5, R = R_raw M, C_r = C_raw^k A^k and
// C = (1 - R) C_t + R C_r. Pixels without a hit show C_t. The MODEL_* bits switch Schlick (R_raw
// = R0) and A (C_r = C_raw) off for the ablations. Dispatched once per mirrored pass over its
// footprint's pixels, `area` (x0, y0, x1, y1): no other pixel's ray hits a plane whose pass ran,
// so the renderer fills the others by a copy of C_t and clears. Where footprints overlap, the
// pixels are composed twice, to the same values.
#include "shared/common.wgsl"
#include "shared/plane_hit.wgsl"

@group(0) @binding(0) var<storage, read> params: ComposeParams;
@group(0) @binding(1) var<storage, read> planes: array<PlaneGpu>;
@group(0) @binding(2) var<storage, read> transmission: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> geometry: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> reflection_raw: array<vec4<f32>>;
// (C, 1 - T_t): the alpha of `transmission`, which the renderer copies outside the area.
@group(0) @binding(5) var<storage, read_write> color: array<vec4<f32>>;
// (C_r, 0)
@group(0) @binding(6) var<storage, read_write> reflection: array<vec4<f32>>;
// (R_raw, R, 0, 0)
@group(0) @binding(7) var<storage, read_write> strength: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> hit: array<u32>;
@group(0) @binding(9) var<storage, read> area: vec4<u32>;

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = gid.x + area.x;
    let y = gid.y + area.y;
    if x >= area.z || y >= area.w {
        return;
    }
    let p = y * params.width + x;
    let trans = transmission[p];
    let ct = trans.xyz;
    let dir = camera_ray(params, x, y);
    let origin = params.origin.xyz;
    var best = -1;
    var best_s = 0.0;
    for (var k = 0u; k < params.num_planes; k++) {
        // A plane whose mirrored pass did not run (switched off, or out of view) is not in the
        // frame: it must not hide a plane behind it.
        if planes[k].normal.w == 0.0 {
            continue;
        }
        let s = rectangle_hit(planes[k], origin, dir);
        if s >= 0.0 && (best < 0 || s < best_s) {
            best = i32(k);
            best_s = s;
        }
    }
    var out_color = ct;
    var out_reflection = vec3<f32>(0.0);
    var out_strength = vec4<f32>(0.0);
    var out_hit = 0u;
    if best >= 0 {
        let plane = planes[best];
        let r0 = plane.centre.w;
        let cos_i = clamp(-dot(plane.normal.xyz, dir), 0.0, 1.0);
        let f = 1.0 - cos_i;
        var r_raw = r0 + (1.0 - r0) * (f * f * f * f * f);
        if (params.model & MODEL_NO_FRESNEL) != 0u {
            r_raw = r0;
        }
        let r = r_raw * geometry[p].z;
        let raw = reflection_raw[u32(best) * params.width * params.height + p];
        let cr = raw.xyz * select(raw.w, 1.0, (params.model & MODEL_NO_INTENSITY) != 0u);
        out_color = (1.0 - r) * ct + r * cr;
        out_reflection = cr;
        out_strength = vec4<f32>(r_raw, r, 0.0, 0.0);
        out_hit = u32(best) + 1u;
    }
    color[p] = vec4<f32>(out_color, trans.w);
    reflection[p] = vec4<f32>(out_reflection, 0.0);
    strength[p] = vec4<f32>(out_strength);
    hit[p] = out_hit;
}
