// Stage `project` (twin: trgs_core::reference::project): EWA projection of every Gaussian for one
// view, which is the real camera or the camera mirrored about a plane (a general 3x3 linear map
// with determinant -1). Culls by depth, opacity, 2D determinant, for a mirrored view the plane's
// front side, and the view's tile limit; writes the screen-space mean, conic, extent, SH colour
// and flags. A culled Gaussian gets flags 0 and nothing else (later stages read no other field of
// it). The tile-limit cull runs twice: first with a bound on the 2D extent from the largest scale,
// before the covariance, then exactly, before the SH evaluation; most of a mirrored view's
// Gaussians fall outside its footprint, and most of any view's outside the image.
#include "shared/common.wgsl"
#include "shared/tiles.wgsl"
#include "shared/sh.wgsl"

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

// Upper bound on the 2D extent along one image axis: the 2D variance (f^2/z^2)(1 + (x/z)^2) of
// the clamped Jacobian row times the largest 3D variance, plus the blur; the relative and absolute
// margins absorb f32 rounding of the exact value computed later.
fn extent_bound(focal: f32, t: f32, iz: f32, var_max: f32, reach: f32) -> f32 {
    let jj = focal * focal * iz * iz * (1.0 + t * t);
    return sqrt(reach * (jj * var_max + COV2D_BLUR)) * 1.001 + 0.01;
}

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = linear_index(gid, nwg, 256u);
    if i >= view.count {
        return;
    }
    var out: ProjectedGaussian;
    let mu = vec3<f32>(means[3u * i], means[3u * i + 1u], means[3u * i + 2u]);
    let glass = populations[i] == POPULATION_GLASS;
    if view.front_only != 0u {
        if glass || !(dot(mu - view.plane_centre.xyz, view.plane_normal.xyz) > 0.0) {
            cull(i);
            return;
        }
    }
    let w = transpose(mat3x3<f32>(view.row0.xyz, view.row1.xyz, view.row2.xyz));
    let p = w * mu + view.translation.xyz;
    if !(p.z >= view.near) {
        cull(i);
        return;
    }
    let opacity = sigmoid(opacity_logits[i]);
    // alpha = o G >= 1/255  <=>  the quadratic form is at most 2 ln(255 o).
    let reach = 2.0 * log(opacity / MIN_ALPHA);
    if !(reach > 0.0) {
        cull(i);
        return;
    }
    let log_s = vec3<f32>(log_scales[3u * i], log_scales[3u * i + 1u], log_scales[3u * i + 2u]);
    let iz = 1.0 / p.z;
    let tx = clamp(p.x / p.z, view.tan_limits.x, view.tan_limits.y);
    let ty = clamp(p.y / p.z, view.tan_limits.z, view.tan_limits.w);
    let mean2d = vec2<f32>(view.focal.x * p.x / p.z + view.focal.z, view.focal.y * p.y / p.z + view.focal.w);
    let var_max = exp(2.0 * max(log_s.x, max(log_s.y, log_s.z)));
    let bound = vec2<f32>(
        extent_bound(view.focal.x, tx, iz, var_max, reach),
        extent_bound(view.focal.y, ty, iz, var_max, reach),
    );
    // Only a finite or infinite bound may cull (tile_rect_of treats NaN as empty).
    if bound.x > 0.0 && bound.y > 0.0 {
        let rough = tile_rect_of(mean2d, bound, view.width, view.height, view.limit);
        if rough.x >= rough.z {
            cull(i);
            return;
        }
    }
    let r = quat_to_mat(rotations[i]);
    let s = exp(log_s);
    let l = mat3x3<f32>(r[0] * s.x, r[1] * s.y, r[2] * s.z);
    let sc = w * (l * transpose(l)) * transpose(w);
    // Jacobian with the mean clamped to the guard band.
    let xc = tx * p.z;
    let yc = ty * p.z;
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
    let extent = vec2<f32>(sqrt(reach * a), sqrt(reach * c));
    let rect = tile_rect_of(mean2d, extent, view.width, view.height, view.limit);
    if rect.x >= rect.z {
        cull(i);
        return;
    }
    let offset = mu - view.centre.xyz;
    let len = length(offset);
    var dir = vec3<f32>(0.0);
    if len > 0.0 {
        dir = offset / len;
    }
    let raw = eval_sh(i, dir);
    var flags = FLAG_VISIBLE;
    if glass {
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
    out.mean2d = mean2d;
    out.extent = extent;
    out.conic = vec4<f32>(c / det, -b / det, a / det, opacity);
    out.color = vec4<f32>(max(raw, vec3<f32>(0.0)), p.z);
    if glass {
        out.mask = sigmoid(mask_logits[i]);
    }
    out.reflection = exp(log_reflections[i]);
    out.flags = flags;
    projected[i] = out;
}
