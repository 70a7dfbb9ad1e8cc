//! Deterministic random scenes for tests and benchmarks, shared by the CPU reference's checks and
//! the GPU stages' comparisons so that both see the same inputs.
use crate::rng::Rng;
use crate::scene::{Camera, Gaussians, Intrinsics, Material, Population, Pose, ReflectionPlane};
use glam::DVec3;

/// A scene to render: Gaussians, planes and one camera.
#[derive(Clone, Debug)]
pub struct Scene {
    pub gaussians: Gaussians<f64>,
    pub planes: Vec<ReflectionPlane>,
    pub camera: Camera,
}

/// How to build a random scene.
#[derive(Clone, Debug)]
pub struct SceneSpec {
    pub seed: u64,
    pub gaussians: usize,
    /// Number of planes (0, 1 or 2).
    pub planes: usize,
    pub width: u32,
    pub height: u32,
    /// Angle in degrees between the normal of the first plane and the direction from the camera
    /// to the plane's centre (80 gives a grazing view).
    pub view_angle_deg: f64,
    pub sh_degree: u32,
    /// Fraction of Gaussians that are glass Gaussians, placed on the first plane.
    pub glass_fraction: f64,
}

impl Default for SceneSpec {
    fn default() -> Self {
        Self {
            seed: 1,
            gaussians: 24,
            planes: 1,
            width: 32,
            height: 24,
            view_angle_deg: 20.0,
            sh_degree: 3,
            glass_fraction: 0.2,
        }
    }
}

fn random_unit(rng: &mut Rng) -> DVec3 {
    DVec3::new(rng.normal(), rng.normal(), rng.normal()).normalize()
}

/// A random scene: the first plane faces the camera at `view_angle_deg`; Gaussians are spread in
/// the camera's frustum (so most are visible) on both sides of the plane, with random rotations,
/// anisotropic scales, opacities, SH coefficients, masks and reflection intensities.
pub fn random_scene(spec: &SceneSpec) -> Scene {
    let mut rng = Rng::new(spec.seed);
    let centre = DVec3::new(0.0, 0.0, 0.0);
    let normal = DVec3::new(0.0, 0.0, 1.0);
    let angle = spec.view_angle_deg.to_radians();
    let eye = centre + 4.0 * DVec3::new(angle.sin(), 0.15 * angle.cos(), angle.cos()).normalize();
    let aim = centre + DVec3::new(0.3 * rng.range(-1.0, 1.0), 0.3 * rng.range(-1.0, 1.0), 0.0);
    let pose = Pose::look_at(eye, aim, DVec3::Y);
    let intr = Intrinsics::from_fov_x(60f64.to_radians(), spec.width, spec.height);
    let camera = Camera::new("random", intr, pose);
    let mut planes = Vec::new();
    if spec.planes >= 1 {
        let n = (normal + 0.05 * random_unit(&mut rng)).normalize();
        planes.push(ReflectionPlane::new(centre, n, DVec3::X, 2.4, 1.8, Material::Glass));
    }
    if spec.planes >= 2 {
        // A mirror to the side, tilted toward the camera, overlapping the first on screen.
        let c2 = DVec3::new(-1.2, 0.2, 0.6);
        let n2 = DVec3::new(0.6, 0.0, 0.8).normalize();
        planes.push(ReflectionPlane::new(c2, n2, DVec3::Y.cross(n2), 1.6, 1.4, Material::Mirror));
    }
    let mut g = Gaussians::<f64>::empty(spec.sh_degree);
    let k = g.sh_coeffs();
    for i in 0..spec.gaussians {
        let glass = spec.planes > 0 && (i as f64) < spec.glass_fraction * spec.gaussians as f64;
        let mean = if glass {
            let p = &planes[0];
            p.centre
                + p.axis * rng.range(-0.45, 0.45) * p.width
                + p.bitangent() * rng.range(-0.45, 0.45) * p.height
        } else {
            // A random pixel and depth, unprojected: visible by construction.
            let (px, py) =
                (rng.range(0.0, f64::from(spec.width)), rng.range(0.0, f64::from(spec.height)));
            let depth = rng.range(1.5, 7.0);
            let d_cam = intr.unproject(px, py) * depth;
            pose.rotation.transpose() * (d_cam - pose.translation)
        };
        let q = random_unit(&mut rng);
        let rot = [rng.range(0.3, 1.0), q.x, q.y, q.z];
        let base = rng.range(-2.8, -1.2);
        let log_scale =
            [base + rng.range(-0.5, 0.5), base + rng.range(-0.5, 0.5), base + rng.range(-0.5, 0.5)];
        let sh: Vec<[f64; 3]> = (0..k)
            .map(|j| {
                let s = if j == 0 { 1.0 } else { 0.25 };
                [s * rng.normal(), s * rng.normal(), s * rng.normal()]
            })
            .collect();
        let pop = if glass { Population::Glass } else { Population::Primary };
        g.push(mean.to_array(), rot, log_scale, rng.range(-1.0, 2.5), &sh, pop);
        let last = g.len() - 1;
        g.mask_logits[last] = if glass { rng.range(0.5, 3.0) } else { 0.0 };
        g.log_reflections[last] = rng.range(-0.3, 0.3);
    }
    Scene { gaussians: g, planes, camera }
}
