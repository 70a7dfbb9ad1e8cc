//! The chain rule from a mirrored view's gradient into its plane's stored parameters. Training
//! runs it on the CPU every step (the GPU sums each view's gradient, `trgs-render`'s
//! `backward::plane_grads` reads the sums back and chains them here), and the CPU reference's
//! backward uses it alike, so it is production code, not a twin.
use crate::plane_math::outer;
use crate::scene::{ReflectionPlane, ViewTransform};
use glam::{DMat3, DVec3};

/// dL/d(view): the view's linear map, translation and centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewGrads {
    pub linear: DMat3,
    pub translation: DVec3,
    pub centre: DVec3,
}

impl Default for ViewGrads {
    fn default() -> Self {
        Self { linear: DMat3::ZERO, translation: DVec3::ZERO, centre: DVec3::ZERO }
    }
}

/// dL/d(plane parameters as stored).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneGrad {
    pub centre: DVec3,
    /// With respect to the unnormalised normal.
    pub normal: DVec3,
    pub r0_logit: f64,
}

/// Chain the gradient of a mirrored view into the plane's centre and unit normal, given the real
/// camera's view. `W' = R H`, `t' = t + 2 (u.n) R n`, `c' = c - 2 ((c - u).n) n`.
pub fn mirrored_view_bwd(
    plane: &ReflectionPlane,
    real: &ViewTransform,
    vg: &ViewGrads,
) -> (DVec3, DVec3) {
    let n = plane.unit_normal();
    let u = plane.centre;
    let (r, c) = (real.linear, real.centre);
    let rn = r * n;
    let mut g_n = -2.0 * (r.transpose() * vg.linear * n + vg.linear.transpose() * rn);
    let gt_rn = vg.translation.dot(rn);
    let mut g_u = 2.0 * gt_rn * n;
    g_n += 2.0 * gt_rn * u + 2.0 * u.dot(n) * (r.transpose() * vg.translation);
    let cu = c - u;
    g_u += 2.0 * n.dot(vg.centre) * n;
    g_n -= 2.0 * (vg.centre.dot(n) * cu + cu.dot(n) * vg.centre);
    (g_u, g_n)
}

/// The gradient of a plane's stored parameters from those of its centre, unit normal and R0:
/// through the normalisation `n = n_raw / |n_raw|` and `R0 = sigmoid(logit)`.
pub fn plane_grad(
    plane: &ReflectionPlane,
    g_centre: DVec3,
    g_unit_normal: DVec3,
    g_r0: f64,
) -> PlaneGrad {
    let len = plane.normal.length();
    let nu = plane.normal / len;
    let r0 = plane.r0();
    PlaneGrad {
        centre: g_centre,
        normal: (DMat3::IDENTITY - outer(nu, nu)) * g_unit_normal / len,
        r0_logit: g_r0 * r0 * (1.0 - r0),
    }
}
