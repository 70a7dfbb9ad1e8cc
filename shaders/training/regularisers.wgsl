// Stage `regularisers` (twin: trgs_core::reference::regularisers): the paper's depth variance,
// gradient conflict and mask losses (section 3.3), one thread per pixel. It writes (overwrites)
// the direct gradients of the transmission layer, dL/d(C_t, alpha) = (w_c dL_c/dC_t, 0), and of
// the geometry layer, dL/d(D_t, V, M, -) = (0, w_d dL_d/dV, w_m dL_m/dM, 0); and each pixel's
// unweighted L_d, L_c and L_m terms for `loss_sums`.
//
// L_c at an interior hit pixel q is, per channel, |g^t(q) . g^r(q)| with g = (g_x, g_y) the
// Sobel derivative estimate (the kernel over 8: units per pixel). Its gradient at pixel p
// gathers, from every such q of p's 3x3 neighbourhood, the taps through which C_t(p) enters q's
// gradient:
// dL_c/dC_t(p) = sum_q sign(g^t(q) . g^r(q)) (K_x(p - q) g_x^r(q) + K_y(p - q) g_y^r(q)) / samples,
// with the reflection side stop-gradient.
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: LossParams;
// (C_t, 1 - T_t)
@group(0) @binding(1) var<storage, read> transmission: array<vec4<f32>>;
// (C_r, 0)
@group(0) @binding(2) var<storage, read> reflection: array<vec4<f32>>;
// (D_t, V, M, 0)
@group(0) @binding(3) var<storage, read> geometry: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> hit: array<u32>;
// Glass labels of the view (> 0: glass; UNCOVERED_LABEL: no source in the photo, no label);
// read only when weight_mask > 0.
@group(0) @binding(5) var<storage, read> annotation: array<u32>;
@group(0) @binding(6) var<storage, read_write> grad_transmission: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> grad_geometry: array<vec4<f32>>;
// Per pixel at 2 p + 1: (H V, sum over channels |g^t . g^r|, |M - M_a|, 0); the photometric
// terms are at 2 p.
@group(0) @binding(8) var<storage, read_write> stats: array<vec4<f32>>;

// The Sobel derivative kernels' tap at offset (dx, dy) in -1..1 (x: horizontal derivative),
// over 8 so that a unit ramp per pixel gives 1.
fn sobel_x(dx: i32, dy: i32) -> f32 {
    return 0.125 * f32(dx) * select(1.0, 2.0, dy == 0);
}

fn sobel_y(dx: i32, dy: i32) -> f32 {
    return 0.125 * f32(dy) * select(1.0, 2.0, dx == 0);
}

// Whether L_c counts at pixel q: its 3x3 neighbourhood is in the image and every pixel of it
// hits the same plane. C_r is zero off the plane's rectangle, so a Sobel window across the
// rectangle's outline would see a step there that no reflection has, and L_c would flatten
// C_t's edges along the outline (the window frame) for it.
fn conflict_pixel(q: vec2<i32>) -> bool {
    let w = i32(params.width);
    let h = i32(params.height);
    if q.x < 1 || q.y < 1 || q.x > w - 2 || q.y > h - 2 {
        return false;
    }
    let plane = hit[u32(q.y) * params.width + u32(q.x)];
    if plane == 0u {
        return false;
    }
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            if hit[u32(q.y + dy) * params.width + u32(q.x + dx)] != plane {
                return false;
            }
        }
    }
    return true;
}

// The Sobel gradients of C_t and C_r at the interior pixel q: (g_x^t, g_y^t, g_x^r, g_y^r).
struct SobelPair {
    tx: vec3<f32>,
    ty: vec3<f32>,
    rx: vec3<f32>,
    ry: vec3<f32>,
}

fn sobel_at(q: vec2<i32>) -> SobelPair {
    var s = SobelPair(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let j = u32(q.y + dy) * params.width + u32(q.x + dx);
            let t = transmission[j].xyz;
            let r = reflection[j].xyz;
            let kx = sobel_x(dx, dy);
            let ky = sobel_y(dx, dy);
            s.tx += kx * t;
            s.ty += ky * t;
            s.rx += kx * r;
            s.ry += ky * r;
        }
    }
    return s;
}

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height {
        return;
    }
    var sum = vec4<f32>(0.0);
    let p = gid.y * params.width + gid.x;
    let here = vec2<i32>(gid.xy);
    var g_geometry = vec4<f32>(0.0);
    if hit[p] != 0u {
        sum.x = geometry[p].y;
        g_geometry.y = params.weight_depth * params.inv_pixels;
    }
    if params.weight_mask > 0.0 && annotation[p] != UNCOVERED_LABEL {
        let d = geometry[p].z - select(0.0, 1.0, annotation[p] > 0u);
        sum.z = abs(d);
        g_geometry.z = params.weight_mask * sign(d) * params.inv_pixels;
    }
    var g_t = vec3<f32>(0.0);
    if params.weight_conflict > 0.0 {
        // The neighbours q where L_c counts, one bit each (offset (dx, dy) at bit 3 (dy + 1) +
        // dx + 1), then a loop over the set bits only: off the planes no bit is set and the loop
        // ends at once. Why not a branch per neighbour: CPU adapters run a branch's body for the
        // whole SIMD vector even when every lane skips it (only loops end early), so each
        // pixel paid nine Sobel windows.
        var taps = 0u;
        for (var k = 0u; k < 9u; k++) {
            let q = here - vec2<i32>(i32(k % 3u) - 1, i32(k / 3u) - 1);
            if conflict_pixel(q) {
                taps |= 1u << k;
            }
        }
        while taps != 0u {
            let k = firstTrailingBit(taps);
            taps &= taps - 1u;
            let dx = i32(k % 3u) - 1;
            let dy = i32(k / 3u) - 1;
            // p = q + (dx, dy): q's tap at (dx, dy) reads p.
            let s = sobel_at(here - vec2<i32>(dx, dy));
            // Per channel, the dot product of the two images' gradients at q.
            let conflict = s.tx * s.rx + s.ty * s.ry;
            if dx == 0 && dy == 0 {
                // q = p: this pixel's own term of L_c.
                sum.y = dot(abs(conflict), vec3<f32>(1.0));
            }
            g_t += sign(conflict) * (sobel_x(dx, dy) * s.rx + sobel_y(dx, dy) * s.ry);
        }
        g_t *= params.weight_conflict * params.inv_samples;
    }
    grad_transmission[p] = vec4<f32>(g_t, 0.0);
    grad_geometry[p] = g_geometry;
    stats[2u * p + 1u] = sum;
}
