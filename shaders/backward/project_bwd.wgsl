// Stage `project_bwd`, the adjoint of `project` (twin: trgs_core::reference::project_bwd): one
// thread per Gaussian of one view that passed the forward's cheap culls (its `candidates` list,
// dispatched indirectly: no other Gaussian can be visible, and on CPU adapters a culled lane would
// cost as much as a visible one), from its screen-space gradients (PROJECTED_GRAD_FLOATS per
// Gaussian, summed by the rasterize adjoints) through the 2D conic and mean, the EWA Jacobian with
// its guard-band clamp, the view's linear map and the SH view direction, to the mean, quaternion,
// log-scales, opacity logit, SH coefficients, mask logit and log reflection intensity. view.bwd_mode
// says how: the primary view writes every listed Gaussian's gradients (zero for culled ones; the
// buffers are cleared before it, for the Gaussians it does not list), a mirrored
// view adds to them (the ADD_GRADIENTS variant) or leaves them alone (BWD_NO_GAUSSIANS, stage
// 2's stop-gradient),
// and with BWD_VIEW the gradient of the view itself (linear map, translation, centre), through
// which the plane learns, is summed over Gaussians into `view_grads`.
#include "shared/common.wgsl"
#include "shared/sh.wgsl"
#include "shared/accumulate.wgsl"

// Whether this variant adds to the gradients (a mirrored view's) or writes them: a constant, so
// that the writing variant never loads what it overwrites (a select on a runtime flag loaded it
// anyway, at a cost `bench --backward` showed).
#ifdef ADD_GRADIENTS
const ADD: bool = true;
#else
const ADD: bool = false;
#endif

@group(0) @binding(0) var<storage, read> view: ProjectParams;
@group(0) @binding(1) var<storage, read> means: array<f32>;
@group(0) @binding(2) var<storage, read> rotations: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> log_scales: array<f32>;
@group(0) @binding(4) var<storage, read> sh: array<f32>;
@group(0) @binding(5) var<storage, read> projected: array<ProjectedGaussian>;
@group(0) @binding(6) var<storage, read> projected_grads: array<vec4<f32>>;
// Gradients in the scene's layout (GpuScene's buffers).
@group(0) @binding(7) var<storage, read_write> g_means: array<f32>;
@group(0) @binding(8) var<storage, read_write> g_rotations: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read_write> g_log_scales: array<f32>;
@group(0) @binding(10) var<storage, read_write> g_opacity_logits: array<f32>;
@group(0) @binding(11) var<storage, read_write> g_sh: array<f32>;
@group(0) @binding(12) var<storage, read_write> g_mask_logits: array<f32>;
@group(0) @binding(13) var<storage, read_write> g_log_reflections: array<f32>;
// VIEW_GRAD_FLOATS of this view: linear map by columns, translation, centre.
#ifdef FLOAT_ATOMICS
@group(0) @binding(14) var<storage, read_write> grads: array<atomic<f32>>;
#else
@group(0) @binding(14) var<storage, read_write> grads: array<atomic<u32>>;
#endif
// The view's list from project_candidates.wgsl and its (workgroups, 1, 1, length).
@group(0) @binding(15) var<storage, read> candidates: array<u32>;
@group(0) @binding(16) var<storage, read> work: array<u32, 4>;

// d(rotation matrix)/dq of a normalised quaternion q = (w, x, y, z), one matrix per component.
fn quat_mat_partial(q: vec4<f32>, m: u32) -> mat3x3<f32> {
    let w = q.x;
    let x = q.y;
    let y = q.z;
    let z = q.w;
    var rows: array<vec3<f32>, 3>;
    switch m {
        case 0u: {
            rows = array(vec3(0.0, -2.0 * z, 2.0 * y), vec3(2.0 * z, 0.0, -2.0 * x), vec3(-2.0 * y, 2.0 * x, 0.0));
        }
        case 1u: {
            rows = array(vec3(0.0, 2.0 * y, 2.0 * z), vec3(2.0 * y, -4.0 * x, -2.0 * w), vec3(2.0 * z, 2.0 * w, -4.0 * x));
        }
        case 2u: {
            rows = array(vec3(-4.0 * y, 2.0 * x, 2.0 * w), vec3(2.0 * x, 0.0, 2.0 * z), vec3(-2.0 * w, 2.0 * z, -4.0 * y));
        }
        default: {
            rows = array(vec3(-4.0 * z, -2.0 * w, 2.0 * x), vec3(2.0 * w, -4.0 * z, 2.0 * y), vec3(2.0 * x, 2.0 * y, 0.0));
        }
    }
    return transpose(mat3x3<f32>(rows[0], rows[1], rows[2]));
}

fn frobenius(a: mat3x3<f32>, b: mat3x3<f32>) -> f32 {
    return dot(a[0], b[0]) + dot(a[1], b[1]) + dot(a[2], b[2]);
}

fn outer(a: vec3<f32>, b: vec3<f32>) -> mat3x3<f32> {
    return mat3x3<f32>(a * b.x, a * b.y, a * b.z);
}

// SH coefficient k (< nk) of Gaussian i: writes (or adds) its gradient basis_k * dL/dcolour
// when `write`, and returns its term of dL/d(direction).
fn sh_term_bwd(
    i: u32,
    k: u32,
    nk: u32,
    basis: f32,
    dbasis: vec3<f32>,
    gcol: vec3<f32>,
    write: bool,
    add: bool,
) -> vec3<f32> {
    if k >= nk {
        return vec3<f32>(0.0);
    }
    let base = (i * nk + k) * 3u;
    let coeff = vec3<f32>(sh[base], sh[base + 1u], sh[base + 2u]);
    if write {
        let gk = basis * gcol;
        g_sh[base] = select(0.0, g_sh[base], add) + gk.x;
        g_sh[base + 1u] = select(0.0, g_sh[base + 1u], add) + gk.y;
        g_sh[base + 2u] = select(0.0, g_sh[base + 2u], add) + gk.z;
    }
    return dot(coeff, gcol) * dbasis;
}

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let in_range = gid.x < work[3];
    var i = 0u;
    if in_range {
        i = candidates[gid.x];
    }
    let mode = view.bwd_mode;
    let add = ADD;
    let write = (mode & BWD_NO_GAUSSIANS) == 0u;
    var visible = false;
    if in_range {
        visible = (projected[i].flags & FLAG_VISIBLE) != 0u;
    }
    // dL/d(view): the linear map's columns, the translation, the centre.
    var vg = mat3x3<f32>(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    var vt = vec3<f32>(0.0);
    var vc = vec3<f32>(0.0);
    if visible {
        let g = projected[i];
        let mu = vec3<f32>(means[3u * i], means[3u * i + 1u], means[3u * i + 2u]);
        let w = transpose(mat3x3<f32>(view.row0.xyz, view.row1.xyz, view.row2.xyz));
        let pc = w * mu + view.translation.xyz;
        let q = rotations[i];
        let r = quat_to_mat(q);
        let s = exp(vec3<f32>(log_scales[3u * i], log_scales[3u * i + 1u], log_scales[3u * i + 2u]));
        let l = mat3x3<f32>(r[0] * s.x, r[1] * s.y, r[2] * s.z);
        let cov3 = l * transpose(l);
        let sc = w * cov3 * transpose(w);
        let fx = view.focal.x;
        let fy = view.focal.y;
        let iz = 1.0 / pc.z;
        let iz2 = iz * iz;
        let tx = pc.x / pc.z;
        let ty = pc.y / pc.z;
        let lim = view.tan_limits;
        let txc = clamp(tx, lim.x, lim.y);
        let tyc = clamp(ty, lim.z, lim.w);
        let xc = txc * pc.z;
        let yc = tyc * pc.z;
        let j0 = vec3<f32>(fx * iz, 0.0, -fx * xc * iz2);
        let j1 = vec3<f32>(0.0, fy * iz, -fy * yc * iz2);
        let s0 = sc * j0;
        let s1 = sc * j1;
        // Q = inverse(cov2d) as the forward stored it: recomputing it here would divide by a
        // determinant that only the forward's guard (0 < det < 3e38) has checked, and would
        // match the forward only while both compile to bit-identical arithmetic.
        let qm = mat2x2<f32>(g.conic.x, g.conic.y, g.conic.y, g.conic.z);

        let pg0 = projected_grads[3u * i];
        let pg1 = projected_grads[3u * i + 1u];
        let pg2 = projected_grads[3u * i + 2u];
        // conic = inverse(cov2d): dL/dcov2d = -Q G_Q Q with G_Q symmetric (b appears twice).
        let gq = mat2x2<f32>(pg1.x, 0.5 * pg1.y, 0.5 * pg1.y, pg1.z);
        let g2 = (qm * gq * qm) * -1.0;
        // cov2d = J Sc J^T + blur: G_Sc = J^T G2 J, G_J = 2 G2 J Sc.
        let g_sc = g2[0][0] * outer(j0, j0) + g2[0][1] * (outer(j0, j1) + outer(j1, j0))
            + g2[1][1] * outer(j1, j1);
        let gj0 = 2.0 * (g2[0][0] * s0 + g2[0][1] * s1);
        let gj1 = 2.0 * (g2[1][0] * s0 + g2[1][1] * s1);
        var gp = vec3<f32>(0.0);
        let g_xc = gj0.z * (-fx * iz2);
        let g_yc = gj1.z * (-fy * iz2);
        // Inside the guard band xc = x; clamped, xc = limit * z.
        if tx > lim.x && tx < lim.y {
            gp.x += g_xc;
        } else {
            gp.z += g_xc * txc;
        }
        if ty > lim.z && ty < lim.w {
            gp.y += g_yc;
        } else {
            gp.z += g_yc * tyc;
        }
        gp.z += gj0.x * (-fx * iz2) + gj0.z * (2.0 * fx * xc * iz2 * iz) + gj1.y * (-fy * iz2)
            + gj1.z * (2.0 * fy * yc * iz2 * iz);
        // mean2d = (fx x / z + cx, fy y / z + cy); depth = z.
        gp.x += pg0.x * fx * iz;
        gp.y += pg0.y * fy * iz;
        gp.z += -(pg0.x * fx * pc.x + pg0.y * fy * pc.y) * iz2 + pg0.w;

        // p = W mu + t;  Sc = W Sigma W^T.
        var g_mu = transpose(w) * gp;
        vg = outer(gp, mu) + 2.0 * g_sc * w * cov3;
        vt = gp;
        let g_cov3 = transpose(w) * g_sc * w;

        // Colour: SH at the unit direction from the view's centre; clamped channels pass nothing.
        let v = mu - view.centre.xyz;
        let len = length(v);
        var dir = vec3<f32>(0.0);
        if len > 0.0 {
            dir = v / len;
        }
        let clamped = vec3<bool>(
            (g.flags & FLAG_CLAMPED_R) != 0u,
            (g.flags & FLAG_CLAMPED_G) != 0u,
            (g.flags & FLAG_CLAMPED_B) != 0u,
        );
        let gcol = select(pg2.xyz, vec3<f32>(0.0), clamped);
        let basis = sh_basis(view.sh_degree, dir);
        let dbasis = sh_basis_grad(view.sh_degree, dir);
        // Constant indices into the basis arrays keep them in registers (a dynamically indexed
        // private array costs a gather per lane on CPU adapters).
        var g_dir = vec3<f32>(0.0);
        let nk = view.sh_coeffs;
        let wr = write;
        g_dir += sh_term_bwd(i, 0u, nk, basis[0], dbasis[0], gcol, wr, add);
        g_dir += sh_term_bwd(i, 1u, nk, basis[1], dbasis[1], gcol, wr, add);
        g_dir += sh_term_bwd(i, 2u, nk, basis[2], dbasis[2], gcol, wr, add);
        g_dir += sh_term_bwd(i, 3u, nk, basis[3], dbasis[3], gcol, wr, add);
        g_dir += sh_term_bwd(i, 4u, nk, basis[4], dbasis[4], gcol, wr, add);
        g_dir += sh_term_bwd(i, 5u, nk, basis[5], dbasis[5], gcol, wr, add);
        g_dir += sh_term_bwd(i, 6u, nk, basis[6], dbasis[6], gcol, wr, add);
        g_dir += sh_term_bwd(i, 7u, nk, basis[7], dbasis[7], gcol, wr, add);
        g_dir += sh_term_bwd(i, 8u, nk, basis[8], dbasis[8], gcol, wr, add);
        g_dir += sh_term_bwd(i, 9u, nk, basis[9], dbasis[9], gcol, wr, add);
        g_dir += sh_term_bwd(i, 10u, nk, basis[10], dbasis[10], gcol, wr, add);
        g_dir += sh_term_bwd(i, 11u, nk, basis[11], dbasis[11], gcol, wr, add);
        g_dir += sh_term_bwd(i, 12u, nk, basis[12], dbasis[12], gcol, wr, add);
        g_dir += sh_term_bwd(i, 13u, nk, basis[13], dbasis[13], gcol, wr, add);
        g_dir += sh_term_bwd(i, 14u, nk, basis[14], dbasis[14], gcol, wr, add);
        g_dir += sh_term_bwd(i, 15u, nk, basis[15], dbasis[15], gcol, wr, add);
        if len > 0.0 {
            let g_v = (g_dir - dir * dot(dir, g_dir)) / len;
            g_mu += g_v;
            vc = -g_v;
        }

        if write {
            // Sigma = L L^T, L = R S.
            let g_l = 2.0 * g_cov3 * l;
            let g_r = mat3x3<f32>(g_l[0] * s.x, g_l[1] * s.y, g_l[2] * s.z);
            let g_ls = vec3<f32>(dot(r[0], g_l[0]), dot(r[1], g_l[1]), dot(r[2], g_l[2])) * s;
            let qn = length(q);
            let qh = q / qn;
            let g_qh = vec4<f32>(
                frobenius(g_r, quat_mat_partial(qh, 0u)),
                frobenius(g_r, quat_mat_partial(qh, 1u)),
                frobenius(g_r, quat_mat_partial(qh, 2u)),
                frobenius(g_r, quat_mat_partial(qh, 3u)),
            );
            let g_q = (g_qh - qh * dot(g_qh, qh)) / qn;
            for (var ax = 0u; ax < 3u; ax++) {
                g_means[3u * i + ax] = select(0.0, g_means[3u * i + ax], add) + g_mu[ax];
                g_log_scales[3u * i + ax] = select(0.0, g_log_scales[3u * i + ax], add) + g_ls[ax];
            }
            g_rotations[i] = select(vec4<f32>(0.0), g_rotations[i], add) + g_q;
            let o = g.conic.w;
            g_opacity_logits[i] = select(0.0, g_opacity_logits[i], add) + pg0.z * o * (1.0 - o);
            var g_mask = 0.0;
            if (g.flags & FLAG_GLASS) != 0u {
                g_mask = pg1.w * g.mask * (1.0 - g.mask);
            }
            g_mask_logits[i] = select(0.0, g_mask_logits[i], add) + g_mask;
            g_log_reflections[i] = select(0.0, g_log_reflections[i], add) + pg2.w * g.reflection;
        }
    } else if in_range && write && !add {
        for (var k = 0u; k < view.sh_coeffs; k++) {
            let base = (i * view.sh_coeffs + k) * 3u;
            g_sh[base] = 0.0;
            g_sh[base + 1u] = 0.0;
            g_sh[base + 2u] = 0.0;
        }
        for (var ax = 0u; ax < 3u; ax++) {
            g_means[3u * i + ax] = 0.0;
            g_log_scales[3u * i + ax] = 0.0;
        }
        g_rotations[i] = vec4<f32>(0.0);
        g_opacity_logits[i] = 0.0;
        g_mask_logits[i] = 0.0;
        g_log_reflections[i] = 0.0;
    }
    // Uniform control flow from here (mode is uniform): every lane takes part in the reductions.
    if (mode & BWD_VIEW) != 0u && subgroup_any(visible) {
        accumulate_subgroup4(0u, vec4<f32>(vg[0], vg[1].x));
        accumulate_subgroup4(4u, vec4<f32>(vg[1].yz, vg[2].xy));
        accumulate_subgroup4(8u, vec4<f32>(vg[2].z, vt));
        accumulate_subgroup4(12u, vec4<f32>(vc, 0.0));
    }
}
