//! A model with planes baked into plain Gaussians, for renderers that know nothing of planes
//! (SuperSplat, Spark, Brush, SIBR, Cesium: every 3DGS viewer but trgs's own).
//!
//! trgs renders `C = (1 - R) C_t + R C_r` over a plane's glass (`reference::compose`), with the
//! strength `R = Schlick(cos) M`. A plain renderer blends Gaussians front to back and has no
//! strength, so the bake approximates each term with Gaussians it can draw:
//!
//! - the glass Gaussians, which only paint the mask `M`, are left out (drawn as splats they are
//!   an opaque slab over the glass);
//! - the reflection becomes the mirrored copies of the primaries on each plane's front side (what
//!   its mirrored pass draws), placed behind the plane where the reflection appears, their colour
//!   times their reflection intensity `a` (`C_r = C_raw A`), their opacity times the strength
//!   seen where the views see them through the glass; a copy no view sees through the glass is
//!   left out (no reflection outside the plane's footprint);
//! - a primary seen through the glass is dimmed by `1 - R` there (its opacity), so that a mirror
//!   hides what lies behind it as trgs's render does.
//!
//! The strength comes from renders of the views (`StrengthView`, the `Strength` layer of trgs's
//! renderer), sampled where each Gaussian's centre lands. Blending by depth cannot order the two
//! layers per pixel as the sum does: where a reflected surface lies farther behind the glass
//! than a seen-through one, the seen-through one hides it. `trgs export` reports how far the
//! baked model's plain render is from trgs's render.
pub mod sh_reflect;

use crate::image::Image;
use crate::plane_math::{householder, ray_rectangle_hit, reflect_point};
use crate::reference::sigmoid;
use crate::scene::{Camera, Gaussians, Population, ReflectionPlane};
use crate::sh::C0;
use glam::{DMat3, DQuat, DVec3};
use sh_reflect::ShTransform;

/// A view and trgs's strength `R` rendered from it (one channel, the camera's size).
#[derive(Clone, Copy, Debug)]
pub struct StrengthView<'a> {
    pub camera: &'a Camera,
    pub strength: &'a Image<f32>,
}

/// What a bake did, for the export's report.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BakeReport {
    /// Glass Gaussians left out.
    pub glass_left_out: usize,
    /// Primaries dimmed because views see them through a plane's glass.
    pub dimmed: usize,
    /// Mirrored copies added, per plane.
    pub mirrored: Vec<usize>,
    /// Front-side primaries whose copy no view sees through the glass, or too faint to draw.
    pub not_seen_mirrored: usize,
}

/// The smallest opacity a plain renderer draws (3DGS skips alpha below 1/255).
const MIN_DRAWN_OPACITY: f64 = 1.0 / 255.0;

/// `gaussians` and `planes` as plain Gaussians (see the module's comment), with the strength
/// seen from `views`. Without planes the primaries come back unchanged.
pub fn bake(
    gaussians: &Gaussians<f32>,
    planes: &[ReflectionPlane],
    views: &[StrengthView],
) -> (Gaussians<f32>, BakeReport) {
    let mut report = BakeReport::default();
    let primaries: Vec<usize> =
        (0..gaussians.len()).filter(|&i| gaussians.populations[i] == Population::Primary).collect();
    report.glass_left_out = gaussians.len() - primaries.len();
    let mut out = gaussians.gather(primaries.iter().copied());
    out.mask_logits.iter_mut().for_each(|m| *m = 0.0);
    out.log_reflections.iter_mut().for_each(|a| *a = 0.0);
    if planes.is_empty() {
        return (out, report);
    }
    let seen_through =
        crate::parallel::map_in_order(&out.means, |m| strength_seen_through(planes, views, m));
    for (i, s) in seen_through.into_iter().enumerate() {
        if s > 0.0 {
            let alpha = sigmoid(f64::from(out.opacity_logits[i])) * (1.0 - s);
            out.opacity_logits[i] = logit(alpha) as f32;
            report.dimmed += 1;
        }
    }
    for plane in planes {
        let mirrored = mirrored_copies(gaussians, &primaries, plane, views);
        report.not_seen_mirrored += mirrored.1;
        report.mirrored.push(mirrored.0.len());
        out.append(&mirrored.0);
    }
    (out, report)
}

/// The mean strength over the views that have `mean` in their image, counting a view whose
/// sightline to it does not cross a plane's glass as zero.
fn strength_seen_through(
    planes: &[ReflectionPlane],
    views: &[StrengthView],
    mean: &[f32; 3],
) -> f64 {
    let x = DVec3::new(f64::from(mean[0]), f64::from(mean[1]), f64::from(mean[2]));
    if planes.iter().all(|p| p.signed_distance(x) >= 0.0) {
        return 0.0;
    }
    let (mut sum, mut n) = (0.0, 0usize);
    for v in views {
        let Some(s) = sample(v, x) else { continue };
        n += 1;
        let c = v.camera.pose.centre();
        let to = x - c;
        let (dir, dist) = (to.normalize(), to.length());
        let crosses = planes.iter().any(|p| {
            p.signed_distance(x) < 0.0 && ray_rectangle_hit(p, c, dir).is_some_and(|t| t < dist)
        });
        if crosses {
            sum += s;
        }
    }
    if n == 0 { 0.0 } else { (sum / n as f64).clamp(0.0, 1.0) }
}

/// The mirrored copies of the front-side primaries of `plane` that some view sees through its
/// glass, and how many were left out.
fn mirrored_copies(
    gaussians: &Gaussians<f32>,
    primaries: &[usize],
    plane: &ReflectionPlane,
    views: &[StrengthView],
) -> (Gaussians<f32>, usize) {
    let h = householder(plane.unit_normal());
    let sh = ShTransform::new(gaussians.sh_degree, h);
    let front: Vec<usize> = primaries
        .iter()
        .copied()
        .filter(|&i| plane.signed_distance(vec3(gaussians.means[i])) > 0.0)
        .collect();
    let strengths = crate::parallel::map_in_order(&front, |&i| {
        strength_of_reflection(plane, views, reflect_point(plane, vec3(gaussians.means[i])))
    });
    let mut out = Gaussians::empty(gaussians.sh_degree);
    let mut left_out = 0;
    for (&i, s) in front.iter().zip(strengths) {
        let alpha = sigmoid(f64::from(gaussians.opacity_logits[i])) * s.unwrap_or(0.0);
        if alpha < MIN_DRAWN_OPACITY {
            left_out += 1;
            continue;
        }
        let mean = reflect_point(plane, vec3(gaussians.means[i]));
        let coeffs: Vec<[f64; 3]> = gaussians.sh_of(i).iter().map(|c| c.map(f64::from)).collect();
        let intensity = f64::from(gaussians.log_reflections[i]).exp();
        let colours = scaled_colour(&sh.apply(&coeffs), intensity);
        let colours: Vec<[f32; 3]> = colours.iter().map(|c| c.map(|v| v as f32)).collect();
        out.push(
            mean.as_vec3().to_array(),
            mirrored_rotation(gaussians.rotations[i], h),
            gaussians.log_scales[i],
            logit(alpha) as f32,
            &colours,
            Population::Primary,
        );
    }
    (out, left_out)
}

/// The mean strength at the virtual point `x` over the views that see it through the plane's
/// glass; None when none does.
fn strength_of_reflection(
    plane: &ReflectionPlane,
    views: &[StrengthView],
    x: DVec3,
) -> Option<f64> {
    let (mut sum, mut n) = (0.0, 0usize);
    for v in views {
        let c = v.camera.pose.centre();
        let Some(dir) = (x - c).try_normalize() else { continue };
        if ray_rectangle_hit(plane, c, dir).is_none() {
            continue;
        }
        let Some(s) = sample(v, x) else { continue };
        sum += s;
        n += 1;
    }
    (n > 0).then(|| (sum / n as f64).clamp(0.0, 1.0))
}

/// The strength at the pixel where `x` lands in the view, if it lands in the image.
fn sample(v: &StrengthView, x: DVec3) -> Option<f64> {
    let p = v.camera.image_point(x)?;
    let (w, h) = (v.strength.width, v.strength.height);
    let (px, py) = (p.x.floor(), p.y.floor());
    if !(px >= 0.0 && py >= 0.0 && px < f64::from(w) && py < f64::from(h)) {
        return None;
    }
    Some(f64::from(v.strength.get(px as u32, py as u32, 0)))
}

/// The rotation of a Gaussian mirrored by `h`: `h R` has determinant -1, so its third axis is
/// flipped, which leaves the covariance `h R S S R^T h` as it is.
fn mirrored_rotation(q: [f32; 4], h: DMat3) -> [f32; 4] {
    let [w, x, y, z] = q.map(f64::from);
    let r = DMat3::from_quat(DQuat::from_xyzw(x, y, z, w).normalize());
    let m = h * r;
    let proper = DMat3::from_cols(m.x_axis, m.y_axis, -m.z_axis);
    let q = DQuat::from_mat3(&proper).normalize();
    [q.w as f32, q.x as f32, q.y as f32, q.z as f32]
}

/// SH coefficients whose colour is `intensity` times that of `c` (before the clamp at zero):
/// `0.5 + C0 dc' + rest' = intensity (0.5 + C0 dc + rest)`.
fn scaled_colour(c: &[[f64; 3]], intensity: f64) -> Vec<[f64; 3]> {
    c.iter()
        .enumerate()
        .map(|(j, v)| {
            v.map(
                |x| {
                    if j == 0 {
                        intensity * x + (intensity - 1.0) * 0.5 / C0
                    } else {
                        intensity * x
                    }
                },
            )
        })
        .collect()
}

fn vec3(m: [f32; 3]) -> DVec3 {
    DVec3::new(f64::from(m[0]), f64::from(m[1]), f64::from(m[2]))
}

/// The logit of an opacity, kept off 0 and 1 so that it stays finite.
fn logit(alpha: f64) -> f64 {
    let a = alpha.clamp(1e-6, 1.0 - 1e-6);
    (a / (1.0 - a)).ln()
}

#[cfg(test)]
mod tests;
