// Stage `compose_bwd` (twin: trgs_core::reference::compose_bwd), the adjoint of `compose`, per
// pixel. The gradient buffers of the pass layers come in holding the loss's direct gradients and
// leave holding the totals: dL/dC_t (and dL/dalpha, passed through), dL/dM, and per plane
// dL/dC_raw and dL/dA. Each plane's dL/dR0 and dL/d(unit normal), through Schlick's cosine, are
// summed over pixels into `grads` (4 floats per plane). H is discrete and passes no gradient.
#include "shared/common.wgsl"
#include "shared/plane_hit.wgsl"
#include "shared/accumulate.wgsl"

@group(0) @binding(0) var<storage, read> params: ComposeParams;
@group(0) @binding(1) var<storage, read> planes: array<PlaneGpu>;
// Forward layers: (C_t, alpha), (D_t, V, M, 0), per plane (C_raw, A), (R_raw, R, 0, 0), H.
@group(0) @binding(2) var<storage, read> transmission: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> geometry: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> reflection_raw: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> strength: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> hit: array<u32>;
// Direct gradients of the composed layers: dL/dC, dL/dC_r, dL/d(R_raw, R).
@group(0) @binding(7) var<storage, read> g_color: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read> g_reflection: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read> g_strength: array<vec4<f32>>;
// Gradients of the pass layers, in: direct, out: total (same layouts as the forward layers).
@group(0) @binding(10) var<storage, read_write> g_transmission: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read_write> g_geometry: array<vec4<f32>>;
@group(0) @binding(12) var<storage, read_write> g_reflection_raw: array<vec4<f32>>;
// Per plane k: [4k] dL/dR0, [4k + 1 .. 4k + 3] dL/d(unit normal).
#ifdef FLOAT_ATOMICS
@group(0) @binding(13) var<storage, read_write> grads: array<atomic<f32>>;
#else
@group(0) @binding(13) var<storage, read_write> grads: array<atomic<u32>>;
#endif

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = gid.x;
    let y = gid.y;
    let inside = x < params.width && y < params.height;
    let p = select(0u, y * params.width + x, inside);
    var k = 0u;
    var g_r0 = 0.0;
    var g_normal = vec3<f32>(0.0);
    let h = select(0u, hit[p], inside);
    if h == 0u {
        if inside {
            let gc = g_color[p].xyz;
            g_transmission[p] = g_transmission[p] + vec4<f32>(gc, 0.0);
        }
    } else {
        k = h - 1u;
        let plane = planes[k];
        let q = k * params.width * params.height + p;
        let raw = reflection_raw[q];
        let st = strength[p];
        let r_raw = st.x;
        let r = st.y;
        let m = geometry[p].z;
        let gc = g_color[p].xyz;
        let ct = transmission[p].xyz;
        let no_intensity = (params.model & MODEL_NO_INTENSITY) != 0u;
        let no_fresnel = (params.model & MODEL_NO_FRESNEL) != 0u;
        let a = select(raw.w, 1.0, no_intensity);
        let cr = raw.xyz * a;
        let g_r = g_strength[p].y + dot(cr - ct, gc);
        let g_cr = g_reflection[p].xyz + r * gc;
        g_transmission[p] = g_transmission[p] + vec4<f32>((1.0 - r) * gc, 0.0);
        let g_a = select(dot(g_cr, raw.xyz), 0.0, no_intensity);
        g_reflection_raw[q] = g_reflection_raw[q] + vec4<f32>(g_cr * a, g_a);
        g_geometry[p] = g_geometry[p] + vec4<f32>(0.0, 0.0, g_r * r_raw, 0.0);
        let g_schlick = g_strength[p].x + g_r * m;
        // Schlick: dR/dR0 = 1 - f^5, dR/dcos = -5 (1 - R0) f^4 with f = 1 - cos.
        let dir = camera_ray(params, x, y);
        let n = plane.normal.xyz;
        let r0 = plane.centre.w;
        let d = -dot(n, dir);
        let cos_i = clamp(d, 0.0, 1.0);
        let f = 1.0 - cos_i;
        let f4 = f * f * f * f;
        g_r0 = g_schlick * select(1.0 - f4 * f, 1.0, no_fresnel);
        // Inside the clamp, cos = -n . d.
        if !no_fresnel && d > 0.0 && d < 1.0 {
            g_normal = g_schlick * (-5.0 * (1.0 - r0) * f4) * (-dir);
        }
    }
    // Uniform control flow from here: every invocation takes part in each plane's reduction.
    for (var j = 0u; j < params.num_planes; j++) {
        let mine = h != 0u && k == j;
        accumulate_subgroup(4u * j, select(0.0, g_r0, mine));
        accumulate_subgroup(4u * j + 1u, select(0.0, g_normal.x, mine));
        accumulate_subgroup(4u * j + 2u, select(0.0, g_normal.y, mine));
        accumulate_subgroup(4u * j + 3u, select(0.0, g_normal.z, mine));
    }
}
