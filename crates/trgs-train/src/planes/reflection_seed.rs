//! Reflection seeding at plane initialisation: Gaussians where only the mirrored passes see
//! them, so that the reflection layer can show what no photo shows directly (the wall behind the
//! photographer). Without them, no primary Gaussian lies in front of a plane where its mirrored
//! pass could render that content, densification has nothing to grow from, the reflection layer
//! stays empty, the strength falls, and the reflected content stays in the transmission layer
//! as plain 3DGS's "virtual" geometry behind the glass. Two sources, both kept only where no
//! training camera sees the spot directly (a Gaussian there would float in front of a camera),
//! nor would see it with its image grown by [`UNSEEN_MARGIN`]: a seed just outside the training
//! views' borders is trained only through the mirrored passes, yet a novel view between them sees
//! it directly as a floater.
//!
//! - [`mirrored_seeds`]: stage 1 (plain 3DGS) may have learnt reflected content as virtual
//!   Gaussians behind the glass; each primary behind a new plane that a training camera sees
//!   through its rectangle gets a copy mirrored to the front. A copy renders in the mirrored
//!   pass exactly where its original renders in the camera's pass.
//! - [`reflected_space_seeds`]: 3DGS's random initialisation for the reflected space: points on
//!   the mirrored rays of random pixels that meet a plane, at random distances beyond it,
//!   coloured as their pixels. Stage 1 is short and starts from SfM points on what the cameras
//!   see, so it rarely holds virtual geometry; these seeds are what the mirrored passes' gradients
//!   train and densification grows.
use glam::{DMat3, DQuat, DVec3};
use trgs_core::Image;
use trgs_core::plane_math::{householder, ray_rectangle_hit, reflect_direction, reflect_point};
use trgs_core::rng::Rng;
use trgs_core::scene::{Camera, Gaussians, Population, ReflectionPlane};
use trgs_core::sh::{C0, C1};

/// How far outside every training image a seed must lie, as a fraction of the image's width and
/// height on each side (see the module's comment). Measured by `family` on the members listed in
/// docs/RESULTS.md, against seeding right up to the image borders.
pub const UNSEEN_MARGIN: f64 = 0.1;

/// Copies of the primary Gaussians of `g` behind each of `planes` that one of `cameras` sees
/// through the plane's rectangle, mirrored to its front where none of `cameras` nearly sees them
/// (within `margin`, see [`Camera::nearly_sees`]). The copies have the originals' opacity, scale
/// and DC colour; the degree-1 band is mirrored with them and higher bands start at zero.
pub fn mirrored_seeds(
    g: &Gaussians<f32>,
    planes: &[ReflectionPlane],
    cameras: &[Camera],
    margin: f64,
) -> Vec<Gaussians<f32>> {
    planes.iter().map(|plane| seeds_of(g, plane, cameras, margin)).collect()
}

fn seeds_of(
    g: &Gaussians<f32>,
    plane: &ReflectionPlane,
    cameras: &[Camera],
    margin: f64,
) -> Gaussians<f32> {
    let mut out = Gaussians::empty(g.sh_degree);
    let n = plane.unit_normal();
    let h = householder(n);
    let front: Vec<&Camera> =
        cameras.iter().filter(|c| plane.signed_distance(c.pose.centre()) > 0.0).collect();
    let coeffs = g.sh_coeffs();
    for i in 0..g.len() {
        if g.populations[i] != Population::Primary {
            continue;
        }
        let mu = DVec3::from_array(g.means[i].map(f64::from));
        if plane.signed_distance(mu) >= 0.0 {
            continue;
        }
        let through = front.iter().any(|c| {
            let to = mu - c.pose.centre();
            ray_rectangle_hit(plane, c.pose.centre(), to.normalize()).is_some()
        });
        let copy = reflect_point(plane, mu);
        if !through || cameras.iter().any(|c| c.nearly_sees(copy, margin)) {
            continue;
        }
        // H R F, F = diag(1, 1, -1): a proper rotation with the mirrored covariance H R S^2 R^T H.
        let [w, x, y, z] = g.rotations[i].map(f64::from);
        let r = DMat3::from_quat(DQuat::from_xyzw(x, y, z, w).normalize());
        let mirrored = h * r * DMat3::from_diagonal(DVec3::new(1.0, 1.0, -1.0));
        let q = DQuat::from_mat3(&mirrored).normalize();
        let mut sh = vec![[0.0f32; 3]; coeffs];
        sh[0] = g.sh_of(i)[0];
        if coeffs >= 4 {
            mirror_band1(&g.sh_of(i)[1..4], &mut sh[1..4], h);
        }
        out.push(
            copy.to_array().map(|v| v as f32),
            [q.w as f32, q.x as f32, q.y as f32, q.z as f32],
            g.log_scales[i],
            g.opacity_logits[i],
            &sh,
            Population::Primary,
        );
    }
    out
}

/// Settings of [`reflected_space_seeds`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReflectedSpaceSeeds {
    /// Gaussians per plane.
    pub count: usize,
    /// Range of distances beyond the plane along the mirrored rays, in scene extents.
    pub near: f64,
    pub far: f64,
    pub opacity: f64,
    /// Kept only where no training camera nearly sees them (see [`Camera::nearly_sees`]).
    pub margin: f64,
}

impl Default for ReflectedSpaceSeeds {
    fn default() -> Self {
        Self { count: 3000, near: 0.1, far: 4.0, opacity: 0.1, margin: UNSEEN_MARGIN }
    }
}

/// Gaussians in the space that the planes reflect and no training camera sees: for random
/// pixels of `views` where the camera's ray meets a plane's rectangle, a point on the mirrored
/// ray at a random distance beyond the plane (log-uniform in `near..far` extents), coloured as
/// the pixel, kept when no camera nearly sees it. 3DGS's random initialisation, for the space
/// where photos of windows show what is behind the photographer; the mirrored passes' gradients
/// then train and densify them as the camera's pass does for the rest.
pub fn reflected_space_seeds(
    views: &[(&Camera, &Image<u8>)],
    planes: &[ReflectionPlane],
    extent: f64,
    settings: &ReflectedSpaceSeeds,
    sh_degree: u32,
    rng: &mut Rng,
) -> Vec<Gaussians<f32>> {
    let logit = (settings.opacity / (1.0 - settings.opacity)).ln() as f32;
    let (ln_near, ln_far) = ((settings.near * extent).ln(), (settings.far * extent).ln());
    planes
        .iter()
        .map(|plane| {
            let mut out = Gaussians::empty(sh_degree);
            let facing: Vec<_> = views
                .iter()
                .filter(|(c, _)| plane.signed_distance(c.pose.centre()) > 0.0)
                .collect();
            if facing.is_empty() {
                return out;
            }
            let coeffs = out.sh_coeffs();
            for _ in 0..settings.count * 20 {
                if out.len() >= settings.count {
                    break;
                }
                let (camera, image) = facing[rng.below(facing.len())];
                let k = &camera.intrinsics;
                let (px, py) =
                    (rng.range(0.0, f64::from(k.width)), rng.range(0.0, f64::from(k.height)));
                let eye = camera.pose.centre();
                let d = camera.pose.direction_to_world(k.unproject(px, py)).normalize();
                let Some(s) = ray_rectangle_hit(plane, eye, d) else { continue };
                let t = (ln_near + rng.uniform() * (ln_far - ln_near)).exp();
                let q = eye + s * d + t * reflect_direction(plane, d);
                if views.iter().any(|(c, _)| c.nearly_sees(q, settings.margin)) {
                    continue;
                }
                // About two pixels wide at its distance along the mirrored ray.
                let log_scale = (2.0 * (s + t) / k.fx).ln() as f32;
                let (x, y) = ((px as u32).min(k.width - 1), (py as u32).min(k.height - 1));
                let mut sh = vec![[0.0f32; 3]; coeffs];
                let colour = |ch| f64::from(image.get(x, y, ch)) / 255.0;
                sh[0] = [0, 1, 2].map(|ch| ((colour(ch) - 0.5) / C0) as f32);
                out.push(
                    q.to_array().map(|v| v as f32),
                    [1.0, 0.0, 0.0, 0.0],
                    [log_scale; 3],
                    logit,
                    &sh,
                    Population::Primary,
                );
            }
            out
        })
        .collect()
}

/// The degree-1 SH band of a colour seen along mirrored directions: the band is `a . d` with
/// `a = C1 (-s3, -s1, s2)`, and the copy must give at `H d` what the original gives at `d`, so
/// `a' = H a`.
fn mirror_band1(band: &[[f32; 3]], out: &mut [[f32; 3]], h: DMat3) {
    for ch in 0..3 {
        let s = |k: usize| f64::from(band[k][ch]);
        let a = h * (C1 * DVec3::new(-s(2), -s(0), s(1)));
        out[0][ch] = (-a.y / C1) as f32;
        out[1][ch] = (a.z / C1) as f32;
        out[2][ch] = (-a.x / C1) as f32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use trgs_core::scene::{Intrinsics, Material, Pose};

    fn plane() -> ReflectionPlane {
        ReflectionPlane::new(DVec3::ZERO, DVec3::Z, DVec3::X, 2.0, 2.0, Material::Glass)
    }

    fn camera_at(eye: DVec3, target: DVec3) -> Camera {
        let k = Intrinsics::from_fov_x(1.0, 64, 48);
        Camera::new("c".to_string(), k, Pose::look_at(eye, target, DVec3::Y))
    }

    #[test]
    fn copies_what_is_seen_through_the_glass_where_no_camera_looks() {
        let cam = camera_at(DVec3::new(0.0, 0.0, 3.0), DVec3::ZERO);
        let mut g = Gaussians::<f32>::empty(1);
        let sh = [[0.5, 0.2, 0.1], [0.1, -0.2, 0.3], [0.05, 0.0, -0.1], [0.2, 0.1, 0.0]];
        // Behind the glass, 5 m: its copy lands 2 m behind the camera.
        g.push(
            [0.1, 0.2, -5.0],
            [1.0, 0.0, 0.0, 0.0],
            [-2.0, -3.0, -4.0],
            0.3,
            &sh,
            Population::Primary,
        );
        // Behind the glass, 1 m: its copy would float 2 m in front of the camera.
        g.push([0.1, 0.2, -1.0], [1.0, 0.0, 0.0, 0.0], [-2.0; 3], 0.3, &sh, Population::Primary);
        // Behind the wall, not through the pane.
        g.push([9.0, 0.0, -5.0], [1.0, 0.0, 0.0, 0.0], [-2.0; 3], 0.3, &sh, Population::Primary);
        // In front of the glass.
        g.push([0.0, 0.0, 1.0], [1.0, 0.0, 0.0, 0.0], [-2.0; 3], 0.3, &sh, Population::Primary);
        let seeds = mirrored_seeds(&g, &[plane()], &[cam], UNSEEN_MARGIN);
        assert_eq!(seeds.len(), 1);
        let s = &seeds[0];
        assert_eq!(s.len(), 1);
        assert_eq!(s.means[0], [0.1, 0.2, 5.0]);
        assert_eq!(s.opacity_logits[0], 0.3);
        assert_eq!(s.populations[0], Population::Primary);
    }

    #[test]
    fn no_copy_just_outside_a_training_image() {
        let cam = camera_at(DVec3::new(0.0, 0.0, 3.0), DVec3::ZERO);
        let mut g = Gaussians::<f32>::empty(0);
        // Seen through the pane (its ray crosses the glass at x = 0.9); the copy at (1.2, 0, 1)
        // is about 3 px outside the 64 px wide image: a neighbouring view would see it float.
        g.push(
            [1.2, 0.0, -1.0],
            [1.0, 0.0, 0.0, 0.0],
            [-2.0; 3],
            0.3,
            &[[0.5; 3]],
            Population::Primary,
        );
        assert!(!cam.sees(DVec3::new(1.2, 0.0, 1.0)));
        let cams = [cam];
        assert_eq!(mirrored_seeds(&g, &[plane()], &cams, 0.0)[0].len(), 1);
        assert_eq!(mirrored_seeds(&g, &[plane()], &cams, UNSEEN_MARGIN)[0].len(), 0);
    }

    #[test]
    fn reflected_space_seeds_lie_where_only_the_mirrored_pass_sees_them() {
        let plane = plane();
        let cams = [
            camera_at(DVec3::new(0.0, 0.0, 3.0), DVec3::ZERO),
            camera_at(DVec3::new(1.0, 0.3, 2.5), DVec3::ZERO),
        ];
        let mut image = Image::<u8>::new(64, 48, 3);
        image.data.iter_mut().enumerate().for_each(|(i, v)| *v = (i % 7 * 36) as u8);
        let views: Vec<_> = cams.iter().map(|c| (c, &image)).collect();
        let settings = ReflectedSpaceSeeds { count: 200, ..Default::default() };
        let mut rng = Rng::new(3);
        let seeds = reflected_space_seeds(&views, &[plane], 2.0, &settings, 1, &mut rng);
        let s = &seeds[0];
        assert_eq!(s.len(), 200);
        for m in &s.means {
            let q = DVec3::from_array(m.map(f64::from));
            assert!(plane.signed_distance(q) > 0.0, "{q} is behind the plane");
            assert!(!cams.iter().any(|c| c.nearly_sees(q, settings.margin)), "{q} is nearly seen");
            // Its mirror image is seen through the rectangle by a camera.
            let image_point = reflect_point(&plane, q);
            assert!(cams.iter().any(|c| {
                let to = (image_point - c.pose.centre()).normalize();
                c.sees(image_point) && ray_rectangle_hit(&plane, c.pose.centre(), to).is_some()
            }));
        }
    }

    #[test]
    fn the_copy_looks_from_the_mirrored_camera_as_the_original_from_the_camera() {
        // A turned plane and a rotated, anisotropic Gaussian with a degree-1 band.
        let plane = ReflectionPlane::new(
            DVec3::new(0.2, -0.1, 0.3),
            DVec3::new(0.3, 0.2, 1.0).normalize(),
            DVec3::new(1.0, 0.0, -0.3).normalize(),
            2.0,
            2.0,
            Material::Glass,
        );
        let mut g = Gaussians::<f32>::empty(1);
        let q = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 0.5).normalize(), 0.7);
        let sh = [[0.5, 0.2, 0.1], [0.1, -0.2, 0.3], [0.05, 0.0, -0.1], [0.2, 0.1, 0.0]];
        let mean = DVec3::new(0.1, 0.0, -4.0);
        g.push(
            mean.to_array().map(|v| v as f32),
            [q.w as f32, q.x as f32, q.y as f32, q.z as f32],
            [-1.0, -2.0, -3.0],
            0.0,
            &sh,
            Population::Primary,
        );
        let cam = camera_at(DVec3::new(0.3, 0.1, 2.0), DVec3::new(0.2, -0.1, 0.3));
        let seeds = &mirrored_seeds(&g, &[plane], &[cam], UNSEEN_MARGIN)[0];
        assert_eq!(seeds.len(), 1);
        // Covariance: the copy's equals H Sigma H.
        let cov = |rot: [f32; 4], s: [f32; 3]| {
            let [w, x, y, z] = rot.map(f64::from);
            let r = DMat3::from_quat(DQuat::from_xyzw(x, y, z, w).normalize());
            let d = DMat3::from_diagonal(DVec3::from_array(s.map(|v| (2.0 * f64::from(v)).exp())));
            r * d * r.transpose()
        };
        let h = householder(plane.unit_normal());
        let want = h * cov(g.rotations[0], g.log_scales[0]) * h;
        let got = cov(seeds.rotations[0], seeds.log_scales[0]);
        assert!((want - got).abs().to_cols_array().iter().all(|&e| e < 1e-6), "{want} vs {got}");
        // Colour: the copy along H d equals the original along d (bands 0 and 1).
        let colour = |sh: &[[f32; 3]], d: DVec3| {
            let b = trgs_core::sh::basis(1, d.normalize().to_array());
            (0..3)
                .map(|ch| (0..4).map(|k| b[k] * f64::from(sh[k][ch])).sum::<f64>())
                .collect::<Vec<_>>()
        };
        for d in [DVec3::new(0.1, 0.2, -1.0), DVec3::new(-0.5, 0.3, -0.8)] {
            let a = colour(g.sh_of(0), d);
            let b = colour(seeds.sh_of(0), reflect_direction(&plane, d));
            assert!(a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-6), "{a:?} vs {b:?}");
        }
    }
}
