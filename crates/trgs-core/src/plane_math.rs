//! Reflection-plane math: the Householder map and what it does to points, directions,
//! covariances and cameras; ray-rectangle hits with the front-side test; nearest-plane selection;
//! Schlick's Fresnel approximation. Every function takes the plane as stored (unnormalised normal).
use crate::image::Image;
use crate::scene::{Camera, Gaussians, Population, Pose, ReflectionPlane, Scalar, ViewTransform};
use glam::{DMat3, DVec3};

/// The linear part `I - 2 n n^T` of the reflection about a plane with unit normal `n`.
pub fn householder(n: DVec3) -> DMat3 {
    DMat3::IDENTITY - 2.0 * outer(n, n)
}

/// `a b^T`.
pub fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// `Hm(x) = x - 2 ((x - u_p) . n) n`.
pub fn reflect_point(plane: &ReflectionPlane, x: DVec3) -> DVec3 {
    let n = plane.unit_normal();
    x - 2.0 * (x - plane.centre).dot(n) * n
}

/// `H d`: directions only see the linear part.
pub fn reflect_direction(plane: &ReflectionPlane, d: DVec3) -> DVec3 {
    let n = plane.unit_normal();
    d - 2.0 * d.dot(n) * n
}

/// `H Sigma H` (H is symmetric).
pub fn reflect_covariance(plane: &ReflectionPlane, sigma: DMat3) -> DMat3 {
    let h = householder(plane.unit_normal());
    h * sigma * h
}

/// The mirrored camera `W' = W Hm`: rendering the unchanged Gaussians with it equals rendering
/// the mirrored Gaussians with `view`. `linear = R H` (det -1), `translation = t + 2 (u_p . n) R n`
/// and the centre is `Hm(c)`.
pub fn mirrored_view(plane: &ReflectionPlane, view: &ViewTransform) -> ViewTransform {
    let n = plane.unit_normal();
    ViewTransform {
        linear: view.linear * householder(n),
        translation: view.translation + 2.0 * plane.centre.dot(n) * (view.linear * n),
        centre: reflect_point(plane, view.centre),
    }
}

/// What the mirrored pass of `plane` sees from `camera`, as an ordinary camera: the mirrored
/// camera `W Hm` with its x axis flipped (a proper rotation again, with `cx` mirrored to match).
/// Rendering [`mirrored_pass_gaussians`] with it over the whole image and applying
/// [`flip_horizontal`] lines the result up with `camera`'s pixels, and where the camera's rays hit
/// the plane it equals the pass's raw reflection C_raw (a twin test checks this); elsewhere it
/// shows the mirrored world that a larger rectangle would show. `render --mirror` uses it to show
/// why a reflection comes out wrong.
pub fn mirror_camera(plane: &ReflectionPlane, camera: &Camera) -> Camera {
    let flip = DMat3::from_diagonal(DVec3::new(-1.0, 1.0, 1.0));
    let n = plane.unit_normal();
    let r = camera.pose.rotation;
    let pose = Pose {
        rotation: flip * r * householder(n),
        translation: flip * (camera.pose.translation + 2.0 * plane.centre.dot(n) * (r * n)),
    };
    let mut intrinsics = camera.intrinsics;
    intrinsics.cx = f64::from(intrinsics.width) - intrinsics.cx;
    Camera::new(format!("{} (mirrored)", camera.name), intrinsics, pose)
}

/// The Gaussians that `plane`'s mirrored pass renders: primaries strictly on its front side.
pub fn mirrored_pass_gaussians<F: Scalar>(
    plane: &ReflectionPlane,
    gaussians: &Gaussians<F>,
) -> Gaussians<F> {
    gaussians.subset(|i| {
        let m = gaussians.means[i];
        let mu = DVec3::new(m[0].to_f64(), m[1].to_f64(), m[2].to_f64());
        gaussians.populations[i] == Population::Primary && plane.signed_distance(mu) > 0.0
    })
}

/// `image` mirrored left-right (undoes the flip of [`mirror_camera`]).
pub fn flip_horizontal<F: Copy>(image: &Image<F>) -> Image<F> {
    let (w, c) = (image.width as usize, image.channels as usize);
    let mut out = image.clone();
    for (src, dst) in image.data.chunks_exact(w * c).zip(out.data.chunks_exact_mut(w * c)) {
        for x in 0..w {
            dst[x * c..(x + 1) * c].copy_from_slice(&src[(w - 1 - x) * c..(w - x) * c]);
        }
    }
    out
}

/// Distance along the ray `origin + s dir` (dir unit) to the plane's rectangle, when the origin is
/// strictly on the front side, the ray goes toward the plane and the hit lies inside the rectangle.
pub fn ray_rectangle_hit(plane: &ReflectionPlane, origin: DVec3, dir: DVec3) -> Option<f64> {
    let n = plane.unit_normal();
    let side = (origin - plane.centre).dot(n);
    let toward = dir.dot(n);
    // Front side only; a ray parallel to the plane (edge-on) or leaving it never hits.
    if !(side > 0.0) || !(toward < 0.0) {
        return None;
    }
    let s = -side / toward;
    if !s.is_finite() {
        return None;
    }
    let local = origin + s * dir - plane.centre;
    let (u, v) = (local.dot(plane.axis), local.dot(plane.bitangent()));
    (u.abs() <= 0.5 * plane.width && v.abs() <= 0.5 * plane.height).then_some(s)
}

/// The nearest plane hit by a ray among the planes that `present` accepts (a plane switched off
/// must not hide one behind it): its index and distance. Ties keep the lower index.
pub fn nearest_plane_hit(
    planes: &[ReflectionPlane],
    present: impl Fn(usize) -> bool,
    origin: DVec3,
    dir: DVec3,
) -> Option<(usize, f64)> {
    let mut best: Option<(usize, f64)> = None;
    for (k, p) in planes.iter().enumerate() {
        if present(k)
            && let Some(s) = ray_rectangle_hit(p, origin, dir)
            && best.is_none_or(|(_, b)| s < b)
        {
            best = Some((k, s));
        }
    }
    best
}

/// `cos = clamp(-n . d, 0, 1)` for a unit ray direction and unit normal.
pub fn incidence_cos(n: DVec3, d: DVec3) -> f64 {
    (-n.dot(d)).clamp(0.0, 1.0)
}

/// Schlick: `R0 + (1 - R0) (1 - cos)^5`.
pub fn schlick(r0: f64, cos: f64) -> f64 {
    r0 + (1.0 - r0) * (1.0 - cos).powi(5)
}

/// Partial derivatives of [`schlick`] with respect to `r0` and `cos`.
pub fn schlick_grad(r0: f64, cos: f64) -> (f64, f64) {
    let m = 1.0 - cos;
    (1.0 - m.powi(5), -5.0 * (1.0 - r0) * m.powi(4))
}
