//! Stage `project`: EWA projection of every Gaussian for one view (the real camera, or the camera
//! mirrored about a plane), with culling, the screen-space extent used for tile binning, and the
//! SH colour for the view direction.
use super::tile_rect;
use crate::pipeline::{COV2D_BLUR, GUARD_BAND, MIN_ALPHA, TileGrid, TileRect};
use crate::scene::{Gaussians, Intrinsics, Population, ReflectionPlane, ViewTransform};
use crate::sh;
use glam::{DMat3, DVec2, DVec3};

/// Which Gaussians a view renders.
#[derive(Clone, Copy, Debug)]
pub enum ProjectionFilter<'a> {
    /// Pass 1: every Gaussian (glass ones only paint the mask).
    All,
    /// Pass 2: primary Gaussians strictly on the front side of the plane.
    FrontOf(&'a ReflectionPlane),
}

/// Projected Gaussians, structure of arrays indexed like the input. Entries of culled Gaussians
/// (`visible[i] == false`) are zero.
#[derive(Clone, Debug, Default)]
pub struct Projected {
    pub visible: Vec<bool>,
    /// Pixel coordinates of the projected mean (pixel centres at +0.5).
    pub mean2d: Vec<DVec2>,
    /// Inverse 2D covariance (a, b, c) of `[[a, b], [b, c]]`.
    pub conic: Vec<[f64; 3]>,
    /// Camera-space depth of the mean.
    pub depth: Vec<f64>,
    /// Half-extents in pixels of the axis-aligned box where alpha can reach 1/255.
    pub extent: Vec<DVec2>,
    /// RGB after the clamp at zero.
    pub color: Vec<[f64; 3]>,
    /// Which channels the clamp at zero cut (their gradient is zero).
    pub color_clamped: Vec<[bool; 3]>,
    pub opacity: Vec<f64>,
    /// Glass mask value m (zero for primary Gaussians).
    pub mask: Vec<f64>,
    /// Reflection intensity a.
    pub reflection: Vec<f64>,
    pub glass: Vec<bool>,
}

impl Projected {
    pub(crate) fn with_len(n: usize) -> Self {
        Self {
            visible: vec![false; n],
            mean2d: vec![DVec2::ZERO; n],
            conic: vec![[0.0; 3]; n],
            depth: vec![0.0; n],
            extent: vec![DVec2::ZERO; n],
            color: vec![[0.0; 3]; n],
            color_clamped: vec![[false; 3]; n],
            opacity: vec![0.0; n],
            mask: vec![0.0; n],
            reflection: vec![0.0; n],
            glass: vec![false; n],
        }
    }

    pub fn len(&self) -> usize {
        self.visible.len()
    }

    pub fn is_empty(&self) -> bool {
        self.visible.is_empty()
    }
}

pub(crate) fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

/// Rotation matrix of the normalised quaternion (w, x, y, z).
pub(crate) fn quat_to_mat(q: [f64; 4]) -> DMat3 {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    let [w, x, y, z] = q.map(|v| v / n);
    DMat3::from_cols(
        DVec3::new(1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + w * z), 2.0 * (x * z - w * y)),
        DVec3::new(2.0 * (x * y - w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z + w * x)),
        DVec3::new(2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y)),
    )
}

/// World-space covariance `R S S R^T` of Gaussian `i`.
pub(crate) fn covariance3d(g: &Gaussians<f64>, i: usize) -> DMat3 {
    let r = quat_to_mat(g.rotations[i]);
    let s = DVec3::from_array(g.log_scales[i].map(f64::exp));
    let l = DMat3::from_cols(r.x_axis * s.x, r.y_axis * s.y, r.z_axis * s.z);
    l * l.transpose()
}

/// The guard-band limits of x/z and y/z for the Jacobian.
pub(crate) fn tan_limits(k: &Intrinsics) -> ([f64; 2], [f64; 2]) {
    let (w, h) = (f64::from(k.width), f64::from(k.height));
    let lx = [(-GUARD_BAND * w - k.cx) / k.fx, ((1.0 + GUARD_BAND) * w - k.cx) / k.fx];
    let ly = [(-GUARD_BAND * h - k.cy) / k.fy, ((1.0 + GUARD_BAND) * h - k.cy) / k.fy];
    (lx, ly)
}

/// The 2x3 projection Jacobian at camera-space point `p` (with the mean clamped to the guard
/// band), as the rows (J00, J02) and (J11, J12); J01 = J10 = 0.
pub(crate) fn jacobian(k: &Intrinsics, p: DVec3) -> [f64; 4] {
    let (lx, ly) = tan_limits(k);
    let xc = (p.x / p.z).clamp(lx[0], lx[1]) * p.z;
    let yc = (p.y / p.z).clamp(ly[0], ly[1]) * p.z;
    let iz = 1.0 / p.z;
    [k.fx * iz, -k.fx * xc * iz * iz, k.fy * iz, -k.fy * yc * iz * iz]
}

/// `J Sigma_c J^T + blur I` as (a, b, c).
pub(crate) fn covariance2d(j: [f64; 4], sc: DMat3) -> [f64; 3] {
    let [j00, j02, j11, j12] = j;
    // Rows of J as 3-vectors.
    let r0 = DVec3::new(j00, 0.0, j02);
    let r1 = DVec3::new(0.0, j11, j12);
    let (s0, s1) = (sc * r0, sc * r1);
    [r0.dot(s0) + COV2D_BLUR, r0.dot(s1), r1.dot(s1) + COV2D_BLUR]
}

/// Project every Gaussian for `view`. A Gaussian is culled when its depth is below `near`, its 2D
/// covariance is not positive definite, its opacity cannot reach 1/255, the filter excludes it, or
/// it touches no tile of `limit` (the whole grid, or a plane's footprint: culled before its SH is
/// evaluated, which is most of a mirrored view's Gaussians).
pub fn project(
    g: &Gaussians<f64>,
    view: &ViewTransform,
    k: &Intrinsics,
    filter: ProjectionFilter<'_>,
    limit: &TileRect,
    near: f64,
) -> Projected {
    let grid = TileGrid::new(k.width, k.height);
    let n = g.len();
    let mut out = Projected::with_len(n);
    for i in 0..n {
        let mu = DVec3::from_array(g.means[i]);
        let glass = g.populations[i] == Population::Glass;
        if let ProjectionFilter::FrontOf(plane) = filter
            && (glass || !(plane.signed_distance(mu) > 0.0))
        {
            continue;
        }
        let p = view.transform_point(mu);
        if !(p.z >= near) {
            continue;
        }
        let opacity = sigmoid(g.opacity_logits[i]);
        // Where alpha >= 1/255: o G >= 1/255 <=> quad form <= 2 ln(255 o).
        let reach = 2.0 * (opacity / MIN_ALPHA).ln();
        if !(reach > 0.0) {
            continue;
        }
        let sc = view.linear * covariance3d(g, i) * view.linear.transpose();
        let [a, b, c] = covariance2d(jacobian(k, p), sc);
        let det = a * c - b * b;
        if !(det > 0.0) || !det.is_finite() {
            continue;
        }
        // The GPU forms the 2D covariance and its determinant in f32 and culls a determinant of
        // 3e38 or more, where f32 overflows (project.wgsl: a Gaussian some 1e7 times larger than
        // the view, log-scale above about 17); the twin culls the same ones instead of keeping a
        // veil the GPU never draws.
        if !(det < 3.0e38) || ![a, c, a * c].iter().all(|&v| (v as f32).is_finite()) {
            continue;
        }
        let mean2d = DVec2::new(k.fx * p.x / p.z + k.cx, k.fy * p.y / p.z + k.cy);
        let extent = DVec2::new((reach * a).sqrt(), (reach * c).sqrt());
        if tile_rect(mean2d, extent, &grid, limit).is_empty() {
            continue;
        }
        let dir = (mu - view.centre).normalize_or_zero();
        let raw = sh::eval(g.sh_degree, g.sh_of(i), dir.to_array());
        out.visible[i] = true;
        out.mean2d[i] = mean2d;
        out.conic[i] = [c / det, -b / det, a / det];
        out.depth[i] = p.z;
        out.extent[i] = extent;
        out.color[i] = raw.map(|v| v.max(0.0));
        out.color_clamped[i] = raw.map(|v| v < 0.0);
        out.opacity[i] = opacity;
        out.mask[i] = if glass { sigmoid(g.mask_logits[i]) } else { 0.0 };
        out.reflection[i] = g.log_reflections[i].exp();
        out.glass[i] = glass;
    }
    out
}
