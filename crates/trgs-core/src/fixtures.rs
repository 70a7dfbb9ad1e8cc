//! Deterministic random scenes for tests and benchmarks, shared by the CPU reference's checks and
//! the GPU stages' comparisons so that both see the same inputs.
use crate::rng::Rng;
use crate::scene::{
    Camera, Gaussians, Intrinsics, Material, Population, Pose, ReflectionPlane, ViewTransform,
};
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
    /// Number of planes (0 to 4; more is refused).
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
    assert!(spec.planes <= 4, "random_scene places at most 4 planes, not {}", spec.planes);
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
    if spec.planes >= 3 {
        // A pane to the other side and a small mirror below, both facing the camera's side.
        let c3 = DVec3::new(1.1, -0.3, 0.4);
        let n3 = DVec3::new(-0.5, 0.1, 0.85).normalize();
        planes.push(ReflectionPlane::new(c3, n3, DVec3::Y.cross(n3), 1.2, 1.0, Material::Glass));
    }
    if spec.planes >= 4 {
        let c4 = DVec3::new(0.2, 0.7, 0.9);
        let n4 = DVec3::new(0.0, -0.3, 0.95).normalize();
        planes.push(ReflectionPlane::new(c4, n4, DVec3::X, 1.0, 0.6, Material::Mirror));
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

/// How to build a benchmark room.
#[derive(Clone, Debug)]
pub struct RoomSpec {
    pub seed: u64,
    pub gaussians: usize,
    /// 0, 1 (a glass pane) or 2 (and a mirror).
    pub planes: usize,
    pub width: u32,
    pub height: u32,
    pub sh_degree: u32,
    pub density: RoomDensity,
}

/// Where a benchmark room's Gaussians are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RoomDensity {
    /// The same world-space density on every wall, as if every wall had been captured from up
    /// close. The mirrored views then see the room behind the camera, farther away and so denser
    /// on screen than the transmitted view.
    Uniform,
    /// As 3DGS densification leaves a capture: surfaces get Gaussians of about constant screen
    /// size in the view that sees them best, the camera's or (through a plane) a mirrored one;
    /// walls that no view sees keep a sparse coarse cover.
    AsCaptured,
}

/// A room for benchmarks, shaped like a real capture: Gaussians on the six walls of a box around
/// the camera (90%) and floating inside it (10%), sized to the wall area per Gaussian so that the
/// depth complexity stays realistic at any count. The camera looks at the far wall; plane 0 is a
/// glass pane in front of it whose screen footprint is at most a quarter of the image (upper
/// left), plane 1 a mirror of the same size (lower right). Their mirrored views see the room
/// behind the camera. `spec.density` says how the Gaussians are spread over the walls.
pub fn room_scene(spec: &RoomSpec) -> Scene {
    let mut rng = Rng::new(spec.seed);
    let room = RoomBox::new(DVec3::new(-4.0, -3.0, -4.0), DVec3::new(4.0, 3.0, 6.0));
    let intr = Intrinsics::from_fov_x(70f64.to_radians(), spec.width, spec.height);
    let camera = Camera::new("room", intr, Pose::default());
    let planes = room_planes(spec, &intr);
    let viewers = RoomViewers::new(&camera, &planes);
    let mut g = Gaussians::<f64>::empty(spec.sh_degree);
    add_room_primaries(&mut g, spec, &room, &viewers, &mut rng);
    add_room_glass(&mut g, spec, &planes, &mut rng);
    Scene { gaussians: g, planes, camera }
}

/// The box of a benchmark room and the areas of its walls.
struct RoomBox {
    lo: DVec3,
    hi: DVec3,
    size: DVec3,
    /// The area of each pair of walls' one wall, by the axis of their normal.
    areas: [f64; 3],
    total_area: f64,
}

impl RoomBox {
    fn new(lo: DVec3, hi: DVec3) -> Self {
        let size = hi - lo;
        let areas = [size.y * size.z, size.x * size.z, size.x * size.y];
        let total_area = 2.0 * (areas[0] + areas[1] + areas[2]);
        Self { lo, hi, size, areas, total_area }
    }

    /// A uniform point inside the room.
    fn inside(&self, rng: &mut Rng) -> DVec3 {
        let p = DVec3::new(rng.uniform(), rng.uniform(), rng.uniform());
        self.lo + p * self.size
    }

    /// A wall chosen by area, a uniform point on it; and the axis of the wall's normal.
    fn wall_point(&self, rng: &mut Rng) -> (DVec3, usize) {
        let mut pick = rng.uniform() * self.total_area;
        let mut axis = 0;
        while axis < 2 && pick >= 2.0 * self.areas[axis] {
            pick -= 2.0 * self.areas[axis];
            axis += 1;
        }
        let mut p = self.lo + DVec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * self.size;
        p[axis] = if rng.uniform() < 0.5 { self.lo[axis] } else { self.hi[axis] };
        (p, axis)
    }
}

/// The planes of a benchmark room: a glass pane over the upper left quarter of the image, then
/// a mirror over the lower right one (as many as `spec.planes` asks, at most two).
fn room_planes(spec: &RoomSpec, intr: &Intrinsics) -> Vec<ReflectionPlane> {
    // A rectangle facing the camera at depth z covering the pixel box [u0, u1] x [v0, v1].
    let pane = |u0: f64, u1: f64, v0: f64, v1: f64, z: f64, material: Material| {
        let (w, h) = (f64::from(spec.width), f64::from(spec.height));
        let a = intr.unproject(u0 * w, v0 * h) * z;
        let b = intr.unproject(u1 * w, v1 * h) * z;
        ReflectionPlane::new(
            0.5 * (a + b),
            DVec3::new(0.0, 0.0, -1.0),
            DVec3::X,
            (b.x - a.x).abs(),
            (b.y - a.y).abs(),
            material,
        )
    };
    let mut planes = Vec::new();
    if spec.planes >= 1 {
        planes.push(pane(0.04, 0.46, 0.04, 0.46, 5.5, Material::Glass));
    }
    if spec.planes >= 2 {
        planes.push(pane(0.54, 0.96, 0.54, 0.96, 5.0, Material::Mirror));
    }
    planes
}

/// The views that see the room: the camera, and the camera mirrored about each plane (which
/// sees through its rectangle only).
struct RoomViewers<'a> {
    camera: &'a Camera,
    view: ViewTransform,
    mirrors: Vec<(ViewTransform, &'a ReflectionPlane)>,
}

impl<'a> RoomViewers<'a> {
    fn new(camera: &'a Camera, planes: &'a [ReflectionPlane]) -> Self {
        let view = ViewTransform::from(&camera.pose);
        let mirrors =
            planes.iter().map(|p| (crate::plane_math::mirrored_view(p, &view), p)).collect();
        Self { camera, view, mirrors }
    }

    /// Where `x` lands on `v`'s image (x, y) and its distance from `v`'s centre; None behind
    /// the near plane.
    fn on_screen(&self, v: &ViewTransform, x: DVec3) -> Option<(f64, f64, f64)> {
        let intr = &self.camera.intrinsics;
        let c = v.transform_point(x);
        (c.z > 0.2).then(|| {
            (intr.fx * c.x / c.z + intr.cx, intr.fy * c.y / c.z + intr.cy, (x - v.centre).length())
        })
    }

    /// Distance from the nearest view that sees `x` (infinite when none does).
    fn distance(&self, x: DVec3) -> f64 {
        let intr = &self.camera.intrinsics;
        let (w, h) = (f64::from(intr.width), f64::from(intr.height));
        let mut best = f64::INFINITY;
        if let Some((u, v, d)) = self.on_screen(&self.view, x)
            && (0.0..w).contains(&u)
            && (0.0..h).contains(&v)
        {
            best = d;
        }
        let eye = self.camera.pose.centre();
        for (mv, plane) in &self.mirrors {
            if plane.signed_distance(x) > 0.0
                && let Some(hit) = crate::plane_math::ray_rectangle_hit(
                    plane,
                    eye,
                    (crate::plane_math::reflect_point(plane, x) - eye).normalize(),
                )
                && hit > 0.0
                && let Some((_, _, d)) = self.on_screen(mv, x)
            {
                best = best.min(d);
            }
        }
        best
    }
}

/// The room's primary Gaussians: on the walls (nine in ten) and floating inside, spread as
/// `spec.density` says.
fn add_room_primaries(
    g: &mut Gaussians<f64>,
    spec: &RoomSpec,
    room: &RoomBox,
    viewers: &RoomViewers<'_>,
    rng: &mut Rng,
) {
    let spacing = (room.total_area / spec.gaussians.max(1) as f64).sqrt();
    let k = g.sh_coeffs();
    // AsCaptured: rejection-sample wall points with density (d_ref / d)^2 (constant screen
    // density); points no view sees get the density of a view 3x farther than the room's size.
    let d_ref = 2.0;
    let unseen = 3.0 * room.size.length();
    let mut tried = 0usize;
    let mut accepted = 0usize;
    let spacing_of = |d: f64| {
        spacing * if spec.density == RoomDensity::Uniform { 1.0 } else { d.max(d_ref) / d_ref }
    };
    for i in 0..spec.gaussians {
        let (mean, flat_axis) = if i % 10 == 9 {
            (room.inside(rng), None)
        } else {
            loop {
                let (p, axis) = room.wall_point(rng);
                if spec.density == RoomDensity::Uniform {
                    break (p, Some(axis));
                }
                tried += 1;
                let d = viewers.distance(p).min(unseen).max(d_ref);
                if rng.uniform() < (d_ref / d).powi(2) {
                    accepted += 1;
                    break (p, Some(axis));
                }
            }
        };
        // Discs in the wall (thin along its normal), random blobs inside. AsCaptured: the spacing
        // grows with the viewing distance (the mean spacing is rescaled below).
        let local = spacing_of(viewers.distance(mean).min(unseen));
        let mut log_scale = [0.0; 3];
        for (a, s) in log_scale.iter_mut().enumerate() {
            let thin = flat_axis == Some(a);
            *s = (local * if thin { 0.1 } else { 0.9 }).ln() + 0.3 * rng.normal();
        }
        let sh: Vec<[f64; 3]> = (0..k)
            .map(|j| {
                let s = if j == 0 { 1.0 } else { 0.15 };
                [s * rng.normal(), s * rng.normal(), s * rng.normal()]
            })
            .collect();
        let q = random_unit(rng) * 0.1;
        let rot = [1.0, q.x, q.y, q.z];
        g.push(mean.to_array(), rot, log_scale, rng.range(-0.5, 3.0), &sh, Population::Primary);
        let last = g.len() - 1;
        g.log_reflections[last] = rng.range(-0.2, 0.2);
    }
    if spec.density == RoomDensity::AsCaptured && tried > 0 {
        // Density (d_ref/d)^2 over the walls integrates to total_area * acceptance; the spacing
        // at d_ref that gives the requested count on that area is sqrt(area * rate / n).
        let rate = accepted as f64 / tried as f64;
        let correction = (rate).sqrt().ln();
        for ls in &mut g.log_scales {
            for v in ls.iter_mut() {
                *v += correction;
            }
        }
    }
}

/// Glass Gaussians on each plane (about 1% of the count): the mask M is about 1 on the panes,
/// as after training.
fn add_room_glass(
    g: &mut Gaussians<f64>,
    spec: &RoomSpec,
    planes: &[ReflectionPlane],
    rng: &mut Rng,
) {
    let k = g.sh_coeffs();
    let per_plane = (spec.gaussians / 100).max(16);
    for p in planes {
        let step = (p.width * p.height / per_plane as f64).sqrt();
        for _ in 0..per_plane {
            let mean = p.centre
                + p.axis * rng.range(-0.5, 0.5) * p.width
                + p.bitangent() * rng.range(-0.5, 0.5) * p.height;
            let sh = vec![[0.0; 3]; k];
            let log_scale = [step.ln(), step.ln(), (0.05 * step).ln()];
            g.push(mean.to_array(), [1.0, 0.0, 0.0, 0.0], log_scale, 0.0, &sh, Population::Glass);
            let last = g.len() - 1;
            g.mask_logits[last] = 3.0;
        }
    }
}
