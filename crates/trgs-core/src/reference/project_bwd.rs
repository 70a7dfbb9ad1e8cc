//! Adjoint of `project`: from the screen-space gradients of one view (2D mean, conic, depth,
//! colour, opacity, mask, reflection intensity) to every Gaussian attribute, and to the view
//! itself (its linear map, translation and centre), through which the plane parameters of a
//! mirrored view learn.
use super::Projected;
use super::project::{covariance2d, covariance3d, jacobian, quat_to_mat, tan_limits};
use crate::plane_grad::ViewGrads;
use crate::plane_math::outer;
use crate::scene::{Gaussians, Intrinsics, ViewTransform};
use crate::sh;
use glam::{DMat3, DVec2, DVec3};

/// dL/d(projected quantities), indexed like the Gaussians.
#[derive(Clone, Debug, Default)]
pub struct ProjectedGrads {
    pub mean2d: Vec<DVec2>,
    pub conic: Vec<[f64; 3]>,
    pub depth: Vec<f64>,
    pub color: Vec<[f64; 3]>,
    pub opacity: Vec<f64>,
    pub mask: Vec<f64>,
    pub reflection: Vec<f64>,
}

impl ProjectedGrads {
    pub fn zeros(n: usize) -> Self {
        Self {
            mean2d: vec![DVec2::ZERO; n],
            conic: vec![[0.0; 3]; n],
            depth: vec![0.0; n],
            color: vec![[0.0; 3]; n],
            opacity: vec![0.0; n],
            mask: vec![0.0; n],
            reflection: vec![0.0; n],
        }
    }
}

/// d(rotation matrix)/d(w, x, y, z) of a normalised quaternion, as four matrices.
fn quat_mat_partials(q: [f64; 4]) -> [DMat3; 4] {
    let [w, x, y, z] = q;
    let m = |rows: [[f64; 3]; 3]| DMat3::from_cols_array_2d(&rows).transpose();
    [
        m([[0.0, -2.0 * z, 2.0 * y], [2.0 * z, 0.0, -2.0 * x], [-2.0 * y, 2.0 * x, 0.0]]),
        m([[0.0, 2.0 * y, 2.0 * z], [2.0 * y, -4.0 * x, -2.0 * w], [2.0 * z, 2.0 * w, -4.0 * x]]),
        m([[-4.0 * y, 2.0 * x, 2.0 * w], [2.0 * x, 0.0, 2.0 * z], [-2.0 * w, 2.0 * z, -4.0 * y]]),
        m([[-4.0 * z, -2.0 * w, 2.0 * x], [2.0 * w, -4.0 * z, 2.0 * y], [2.0 * x, 2.0 * y, 0.0]]),
    ]
}

/// Frobenius inner product.
fn dot3(a: &DMat3, b: &DMat3) -> f64 {
    a.x_axis.dot(b.x_axis) + a.y_axis.dot(b.y_axis) + a.z_axis.dot(b.z_axis)
}

/// Backpropagate one view's screen-space gradients. Gaussian gradients are added to `out` when it
/// is given (the stage-2 stop-gradient passes None for mirrored views); the view's gradient is
/// returned either way.
pub fn project_bwd(
    g: &Gaussians<f64>,
    view: &ViewTransform,
    k: &Intrinsics,
    p: &Projected,
    pg: &ProjectedGrads,
    mut out: Option<&mut Gaussians<f64>>,
) -> ViewGrads {
    let mut vg = ViewGrads::default();
    let limits = tan_limits(k);
    let ncoef = g.sh_coeffs();
    for i in 0..g.len() {
        if !p.visible[i] {
            continue;
        }
        let mu = DVec3::from_array(g.means[i]);
        let pc = view.transform_point(mu);
        let cov3 = covariance3d(g, i);
        let sc = view.linear * cov3 * view.linear.transpose();
        let j = jacobian(k, pc);
        let (g_sc, gj_rows) = covariance2d_bwd(j, sc, pg.conic[i]);
        let gp = camera_point_bwd(k, limits, pc, gj_rows, pg.mean2d[i], pg.depth[i]);

        // p = W mu + t.
        let mut g_mu = view.linear.transpose() * gp;
        vg.linear += outer(gp, mu);
        vg.translation += gp;
        // Sc = W Sigma W^T.
        let g_cov3 = view.linear.transpose() * g_sc * view.linear;
        vg.linear += 2.0 * g_sc * view.linear * cov3;

        let gcol: [f64; 3] =
            [0, 1, 2].map(|ch| if p.color_clamped[i][ch] { 0.0 } else { pg.color[i][ch] });
        let (basis, g_v) = colour_bwd(g, i, view.centre, gcol);
        if let Some(g_v) = g_v {
            g_mu += g_v;
            vg.centre -= g_v;
        }

        let Some(out) = out.as_deref_mut() else { continue };
        for kk in 0..ncoef {
            for ch in 0..3 {
                out.sh[i * ncoef + kk][ch] += basis[kk] * gcol[ch];
            }
        }
        let (g_log_scale, g_rotation) = covariance3d_bwd(g.rotations[i], g.log_scales[i], g_cov3);
        for ax in 0..3 {
            out.log_scales[i][ax] += g_log_scale[ax];
        }
        for m in 0..4 {
            out.rotations[i][m] += g_rotation[m];
        }
        for ax in 0..3 {
            out.means[i][ax] += g_mu[ax];
        }
        let o = p.opacity[i];
        out.opacity_logits[i] += pg.opacity[i] * o * (1.0 - o);
        if p.glass[i] {
            let m = p.mask[i];
            out.mask_logits[i] += pg.mask[i] * m * (1.0 - m);
        }
        out.log_reflections[i] += pg.reflection[i] * p.reflection[i];
    }
    vg
}

/// From dL/d(conic) to dL/dSc (the view-space covariance) and dL/d(the two rows of the
/// projection's Jacobian J).
fn covariance2d_bwd(j: [f64; 4], sc: DMat3, g_conic: [f64; 3]) -> (DMat3, [DVec3; 2]) {
    let [a, b, c] = covariance2d(j, sc);
    let det = a * c - b * b;
    let q2 = [[c / det, -b / det], [-b / det, a / det]];

    // conic = inverse(cov2d): dL/dSigma2 = -Q G_Q Q with G_Q symmetric (b appears twice).
    let [gca, gcb, gcc] = g_conic;
    let gq = [[gca, 0.5 * gcb], [0.5 * gcb, gcc]];
    let mut g2 = [[0.0; 2]; 2];
    for r in 0..2 {
        for s in 0..2 {
            let mut v = 0.0;
            for u in 0..2 {
                for t in 0..2 {
                    v -= q2[r][u] * gq[u][t] * q2[t][s];
                }
            }
            g2[r][s] = v;
        }
    }
    // cov2d = J Sc J^T + blur: G_Sc = J^T G2 J, G_J = 2 G2 J Sc.
    let [j00, j02, j11, j12] = j;
    let jr = [DVec3::new(j00, 0.0, j02), DVec3::new(0.0, j11, j12)];
    let mut g_sc = DMat3::ZERO;
    for r in 0..2 {
        for s in 0..2 {
            g_sc += g2[r][s] * outer(jr[r], jr[s]);
        }
    }
    let gj_rows = [
        2.0 * (g2[0][0] * (sc * jr[0]) + g2[0][1] * (sc * jr[1])),
        2.0 * (g2[1][0] * (sc * jr[0]) + g2[1][1] * (sc * jr[1])),
    ];
    (g_sc, gj_rows)
}

/// dL/d(camera-space mean `pc`): through the Jacobian (`gj_rows`, its rows' gradients), whose
/// mean is clamped to the guard band `limits` (tan x, tan y), and through the 2D mean and the
/// depth (`gm`, `g_depth`).
fn camera_point_bwd(
    k: &Intrinsics,
    (lx, ly): ([f64; 2], [f64; 2]),
    pc: DVec3,
    gj_rows: [DVec3; 2],
    gm: DVec2,
    g_depth: f64,
) -> DVec3 {
    let (iz, iz2) = (1.0 / pc.z, 1.0 / (pc.z * pc.z));
    let (tx, ty) = (pc.x / pc.z, pc.y / pc.z);
    let xc = tx.clamp(lx[0], lx[1]) * pc.z;
    let yc = ty.clamp(ly[0], ly[1]) * pc.z;
    let mut gp = DVec3::ZERO;
    let g_xc = gj_rows[0].z * (-k.fx * iz2);
    let g_yc = gj_rows[1].z * (-k.fy * iz2);
    // Inside the guard band xc = x; clamped, xc = limit * z.
    if tx > lx[0] && tx < lx[1] {
        gp.x += g_xc;
    } else {
        gp.z += g_xc * tx.clamp(lx[0], lx[1]);
    }
    if ty > ly[0] && ty < ly[1] {
        gp.y += g_yc;
    } else {
        gp.z += g_yc * ty.clamp(ly[0], ly[1]);
    }
    gp.z += gj_rows[0].x * (-k.fx * iz2)
        + gj_rows[0].z * (2.0 * k.fx * xc * iz2 * iz)
        + gj_rows[1].y * (-k.fy * iz2)
        + gj_rows[1].z * (2.0 * k.fy * yc * iz2 * iz);
    // mean2d = (fx x / z + cx, fy y / z + cy); depth = z.
    gp.x += gm.x * k.fx * iz;
    gp.y += gm.y * k.fy * iz;
    gp.z += -(gm.x * k.fx * pc.x + gm.y * k.fy * pc.y) * iz2 + g_depth;
    gp
}

/// Colour: SH at the unit direction from the view's centre. The SH basis there (the
/// coefficients' gradient is it times `gcol`, dL/d(colour)) and dL/d(mean) through the
/// direction, None for a mean at the centre.
fn colour_bwd(
    g: &Gaussians<f64>,
    i: usize,
    centre: DVec3,
    gcol: [f64; 3],
) -> ([f64; 16], Option<DVec3>) {
    let v = DVec3::from_array(g.means[i]) - centre;
    let len = v.length();
    let mut g_dir = DVec3::ZERO;
    let dir = if len > 0.0 { v / len } else { DVec3::ZERO };
    let basis = sh::basis(g.sh_degree, dir.to_array());
    let dbasis = sh::basis_grad(g.sh_degree, dir.to_array());
    let coeffs = g.sh_of(i);
    for kk in 0..g.sh_coeffs() {
        let s = coeffs[kk][0] * gcol[0] + coeffs[kk][1] * gcol[1] + coeffs[kk][2] * gcol[2];
        g_dir += s * DVec3::from_array(dbasis[kk]);
    }
    let g_v = (len > 0.0).then(|| (g_dir - dir * dir.dot(g_dir)) / len);
    (basis, g_v)
}

/// Sigma = L L^T, L = R S: from dL/dSigma to dL/d(log-scales) and dL/d(the quaternion as
/// stored, unnormalised).
fn covariance3d_bwd(q: [f64; 4], log_scale: [f64; 3], g_cov3: DMat3) -> ([f64; 3], [f64; 4]) {
    let qn = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    let qh = q.map(|v| v / qn);
    let r = quat_to_mat(q);
    let s = DVec3::from_array(log_scale.map(f64::exp));
    let l = DMat3::from_cols(r.x_axis * s.x, r.y_axis * s.y, r.z_axis * s.z);
    let g_l = 2.0 * g_cov3 * l;
    let g_r = DMat3::from_cols(g_l.x_axis * s.x, g_l.y_axis * s.y, g_l.z_axis * s.z);
    let g_s =
        DVec3::new(r.x_axis.dot(g_l.x_axis), r.y_axis.dot(g_l.y_axis), r.z_axis.dot(g_l.z_axis));
    let g_log_scale = [0, 1, 2].map(|ax| g_s[ax] * s[ax]);
    let partials = quat_mat_partials(qh);
    let g_qh: [f64; 4] = [0, 1, 2, 3].map(|m| dot3(&g_r, &partials[m]));
    let proj = g_qh.iter().zip(qh).map(|(a, b)| a * b).sum::<f64>();
    let g_rotation = [0, 1, 2, 3].map(|m| (g_qh[m] - qh[m] * proj) / qn);
    (g_log_scale, g_rotation)
}
