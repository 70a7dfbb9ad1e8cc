// Stage `project` (twin: trgs_core::reference::project), second kernel: EWA projection for one
// view, which is the real camera or the camera mirrored about a plane (a general 3x3 linear map
// with determinant -1), of the Gaussians that project_candidates.wgsl listed after the cheap
// culls (depth, opacity, a mirrored view's front side, a bound on the extent against the view's
// tile limit). Culls by the 2D determinant and the exact tile rectangle; writes the screen-space
// mean, conic, extent, SH colour and flags. A culled Gaussian gets flags 0 and nothing else
// (later stages read no other field of it). Most of a mirrored view's Gaussians fall outside its
// footprint, and most of any view's outside the image: they never get here.
#include "shared/common.wgsl"
#include "shared/tiles.wgsl"
#include "shared/sh.wgsl"
#include "shared/project_cull.wgsl"

@group(0) @binding(0) var<storage, read> view: ProjectParams;
@group(0) @binding(1) var<storage, read> means: array<f32>;
@group(0) @binding(2) var<storage, read> rotations: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> log_scales: array<f32>;
@group(0) @binding(4) var<storage, read> opacity_logits: array<f32>;
@group(0) @binding(5) var<storage, read> sh: array<f32>;
@group(0) @binding(6) var<storage, read> mask_logits: array<f32>;
@group(0) @binding(7) var<storage, read> log_reflections: array<f32>;
@group(0) @binding(8) var<storage, read> populations: array<u32>;
@group(0) @binding(9) var<storage, read_write> projected: array<ProjectedGaussian>;
// The list and its indirect dispatch (workgroups, 1, 1, list length) from project_candidates.
@group(0) @binding(10) var<storage, read> candidates: array<u32>;
@group(0) @binding(11) var<storage, read> work: array<u32, 4>;

fn sh_coeff(i: u32, k: u32) -> vec3<f32> {
    let base = (i * view.sh_coeffs + k) * 3u;
    return vec3<f32>(sh[base], sh[base + 1u], sh[base + 2u]);
}

// 3DGS's SH evaluation (+0.5 offset), before the clamp at zero.
// Constant indices into the basis keep it in registers (a dynamically indexed private array
// costs a gather per lane on CPU adapters).
fn eval_sh(i: u32, d: vec3<f32>) -> vec3<f32> {
    let b = sh_basis(view.sh_degree, d);
    var rgb = vec3<f32>(0.5);
    rgb += sh_term(i, 0u, b[0]);
    rgb += sh_term(i, 1u, b[1]);
    rgb += sh_term(i, 2u, b[2]);
    rgb += sh_term(i, 3u, b[3]);
    rgb += sh_term(i, 4u, b[4]);
    rgb += sh_term(i, 5u, b[5]);
    rgb += sh_term(i, 6u, b[6]);
    rgb += sh_term(i, 7u, b[7]);
    rgb += sh_term(i, 8u, b[8]);
    rgb += sh_term(i, 9u, b[9]);
    rgb += sh_term(i, 10u, b[10]);
    rgb += sh_term(i, 11u, b[11]);
    rgb += sh_term(i, 12u, b[12]);
    rgb += sh_term(i, 13u, b[13]);
    rgb += sh_term(i, 14u, b[14]);
    rgb += sh_term(i, 15u, b[15]);
    return rgb;
}

fn sh_term(i: u32, k: u32, basis: f32) -> vec3<f32> {
    if k >= view.sh_coeffs {
        return vec3<f32>(0.0);
    }
    return basis * sh_coeff(i, k);
}

fn cull(i: u32) {
    projected[i].flags = 0u;
}

// One thread per listed Gaussian (each passed the cheap culls).
@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x < work[3] {
        project_one(candidates[gid.x]);
    }
}

fn project_one(i: u32) {
    var out: ProjectedGaussian;
    let v = in_view(view, gaussian_point(i));
    let w = transpose(mat3x3<f32>(view.row0.xyz, view.row1.xyz, view.row2.xyz));
    let p = v.p;
    let iz = 1.0 / p.z;
    let r = quat_to_mat(rotations[i]);
    let s = exp(v.g.log_s);
    let l = mat3x3<f32>(r[0] * s.x, r[1] * s.y, r[2] * s.z);
    let sc = w * (l * transpose(l)) * transpose(w);
    // Jacobian with the mean clamped to the guard band.
    let xc = v.tx * p.z;
    let yc = v.ty * p.z;
    let r0 = vec3<f32>(view.focal.x * iz, 0.0, -view.focal.x * xc * iz * iz);
    let r1 = vec3<f32>(0.0, view.focal.y * iz, -view.focal.y * yc * iz * iz);
    let s0 = sc * r0;
    let s1 = sc * r1;
    let a = dot(r0, s0) + COV2D_BLUR;
    let b = dot(r0, s1);
    let c = dot(r1, s1) + COV2D_BLUR;
    let det = a * c - b * b;
    // det > 0 and finite (the second test rejects +Inf and NaN).
    if !(det > 0.0) || !(det < 3.0e38) {
        cull(i);
        return;
    }
    let extent = vec2<f32>(sqrt(v.g.reach * a), sqrt(v.g.reach * c));
    let rect = tile_rect_of(v.mean2d, extent, view.width, view.height, view.limit);
    if rect.x >= rect.z {
        cull(i);
        return;
    }
    let offset = v.g.mu - view.centre.xyz;
    let len = length(offset);
    var dir = vec3<f32>(0.0);
    if len > 0.0 {
        dir = offset / len;
    }
    let raw = eval_sh(i, dir);
    var flags = FLAG_VISIBLE;
    if v.g.glass {
        flags |= FLAG_GLASS;
    }
    if raw.x < 0.0 {
        flags |= FLAG_CLAMPED_R;
    }
    if raw.y < 0.0 {
        flags |= FLAG_CLAMPED_G;
    }
    if raw.z < 0.0 {
        flags |= FLAG_CLAMPED_B;
    }
    out.mean2d = v.mean2d;
    out.extent = extent;
    out.conic = vec4<f32>(c / det, -b / det, a / det, v.g.opacity);
    out.color = vec4<f32>(max(raw, vec3<f32>(0.0)), p.z);
    if v.g.glass {
        out.mask = sigmoid(mask_logits[i]);
    }
    out.reflection = exp(log_reflections[i]);
    out.flags = flags;
    projected[i] = out;
}
