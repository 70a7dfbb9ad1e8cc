//! Scene layout: the world, the camera loop and the truth planes ([`Plan`](super::plan) turns
//! it into the photos' cameras, points and masks; `render_views` traces it).
use std::f64::consts::PI;

use glam::{DMat3, DVec3};

use super::config::{Backdrop, GLASS_R0, MIRROR_R0, PaneKind, Setting, SyntheticConfig};
use super::geom::{Ray, Rect, Turn};
use super::paths::{camera_path, room_view_path};
use super::room::{FRONT_DEPTH, HALF_WIDTH, HEIGHT};
use super::street;
use super::texture::Texture;
use super::trace::{Object, Pane, Shape, World};
use trgs_core::lens::Distortion;
use trgs_core::scene::{Camera, Intrinsics, Material, Pose, ReflectionPlane};

/// Subsamples per pixel side: 2x2 rays per pixel.
pub(crate) const SUPERSAMPLE: u32 = 2;

/// Horizontal field of view of every camera.
const FOV_X_DEG: f64 = 62.0;

/// Pane centre height and frame bar width (the pane's size is [`Backdrop::pane_size`]).
const PANE_Y: f64 = 1.2;
const FRAME_W: f64 = 0.07;
/// Height of the window wall's centre.
const WALL_Y: f64 = 0.5 * HEIGHT;

/// Tallest pane the wall holds around [`PANE_Y`] with its frame and sill.
const MAX_PANE_H: f64 = 2.1;

/// Centres (x, y) of the light panels on the wall behind the cameras, in the order
/// [`SyntheticConfig::reflected_lights`] adds them, and their half size.
const LIGHT_SPOTS: [(f64, f64); 4] = [(-1.3, 1.95), (1.0, 1.8), (0.1, 2.35), (-2.3, 1.5)];
const LIGHT_HALF: [f64; 2] = [0.35, 0.22];

/// Lighting gain of the light panels: they shine 2 to 3 times brighter than white, so that even
/// clear glass shows them clearly, as lamps in photos of windows; seen directly they saturate.
const LIGHT_GAIN: f64 = 4.0;

impl Backdrop {
    /// Depth of the room behind the pane wall.
    fn depth(self) -> f64 {
        match self {
            Backdrop::Room => 4.5,
            Backdrop::Showcase => 1.6,
        }
    }

    /// Width of a single pane and the height of every pane.
    fn pane_size(self) -> (f64, f64) {
        match self {
            Backdrop::Room => (1.6, 1.0),
            Backdrop::Showcase => (2.4, 1.4),
        }
    }
}

/// The local scene frame in the world: `x_world = rotation * x_local + translation`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Placement {
    pub rotation: DMat3,
    pub translation: DVec3,
}

impl Placement {
    /// A fixed, deliberately not axis-aligned placement with world up roughly along -y.
    fn fixed() -> Self {
        let tilt = DMat3::from_axis_angle(DVec3::new(0.3, 0.2, 1.0).normalize(), 0.35);
        Self {
            rotation: tilt * DMat3::from_rotation_x(PI),
            translation: DVec3::new(0.7, -0.4, 1.9),
        }
    }

    pub fn point_to_world(&self, p: DVec3) -> DVec3 {
        self.rotation * p + self.translation
    }

    pub fn point_to_local(&self, p: DVec3) -> DVec3 {
        self.rotation.transpose() * (p - self.translation)
    }

    pub fn dir_to_local(&self, d: DVec3) -> DVec3 {
        self.rotation.transpose() * d
    }
}

/// Everything `generate` derives before rendering: the tracer's world, its placement, cameras and
/// truth planes. Tests use it for independent checks.
#[derive(Clone, Debug)]
pub(crate) struct Layout {
    pub world: World,
    pub placement: Placement,
    pub cameras: Vec<Camera>,
    pub planes: Vec<ReflectionPlane>,
    /// Frame bars and sills (local boxes), sampled preferentially for sparse points.
    pub frame_boxes: Boxes,
    /// The photos' lens distortion (None: pinhole photos).
    pub lens: Option<Distortion>,
}

pub(crate) const fn rgb(r: f64, g: f64, b: f64) -> DVec3 {
    DVec3::new(r, g, b)
}

pub(crate) fn cuboid(min: [f64; 3], max: [f64; 3], texture: Texture) -> Object {
    Object {
        shape: Shape::Cuboid { min: min.into(), max: max.into(), turn: None },
        texture,
        gain: 1.0,
    }
}

pub(crate) fn sphere(centre: [f64; 3], radius: f64, texture: Texture) -> Object {
    Object { shape: Shape::Sphere { centre: centre.into(), radius }, texture, gain: 1.0 }
}

/// An axis-aligned wall given by its centre, its two in-plane axes and half sizes.
pub(crate) fn quad(
    centre: [f64; 3],
    u: DVec3,
    v: DVec3,
    half: [f64; 2],
    texture: Texture,
) -> Object {
    let rect = Rect { centre: centre.into(), u, v, half_u: half[0], half_v: half[1] };
    Object { shape: Shape::Quad { rect, holes: Vec::new() }, texture, gain: 1.0 }
}

/// Width of each pane and x of each pane centre: one pane is `single` wide; several share 3.2 m
/// with 0.45 m of wall between them (the layout is meant for up to four).
fn pane_slots(n: usize, single: f64) -> (f64, Vec<f64>) {
    const GAP: f64 = 0.45;
    let w = if n == 1 { single } else { ((3.2 - GAP * (n as f64 - 1.0)) / n as f64).max(0.3) };
    let xs = (0..n).map(|k| (k as f64 - 0.5 * (n as f64 - 1.0)) * (w + GAP)).collect();
    (w, xs)
}

/// The room behind the pane wall, `bd` deep: floor, ceiling, side walls and a brick back wall.
fn behind_shell(bd: f64) -> Vec<Object> {
    let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
    let (hw, ht) = (HALF_WIDTH, HEIGHT);
    vec![
        quad(
            [0.0, 0.0, -0.5 * bd],
            x,
            z,
            [hw, 0.5 * bd],
            Texture::Checker { period: 0.35, a: rgb(0.85, 0.85, 0.82), b: rgb(0.18, 0.20, 0.24) },
        ),
        quad(
            [0.0, ht, -0.5 * bd],
            x,
            z,
            [hw, 0.5 * bd],
            Texture::Plain { colour: rgb(0.85, 0.85, 0.88), grain: 0.1 },
        ),
        quad(
            [-hw, 0.5 * ht, -0.5 * bd],
            z,
            y,
            [0.5 * bd, 0.5 * ht],
            Texture::Noise { scale: 0.25, a: rgb(0.75, 0.80, 0.45), b: rgb(0.30, 0.45, 0.25) },
        ),
        quad(
            [hw, 0.5 * ht, -0.5 * bd],
            z,
            y,
            [0.5 * bd, 0.5 * ht],
            Texture::Stripes { period: 0.4, a: rgb(0.78, 0.62, 0.75), b: rgb(0.45, 0.30, 0.55) },
        ),
        quad(
            [0.0, 0.5 * ht, -bd],
            x,
            y,
            [hw, 0.5 * ht],
            Texture::Bricks {
                width: 0.3,
                height: 0.1,
                brick: rgb(0.70, 0.32, 0.20),
                mortar: rgb(0.80, 0.78, 0.72),
            },
        ),
    ]
}

/// Textures of the objects behind the glass, which both backdrops share: the showcase displays
/// the same objects as the room, nearer the glass.
pub(crate) const RED_STRIPES: Texture =
    Texture::Stripes { period: 0.16, a: rgb(0.85, 0.20, 0.18), b: rgb(0.92, 0.90, 0.85) };
pub(crate) const AMBER_NOISE: Texture =
    Texture::Noise { scale: 0.12, a: rgb(0.95, 0.70, 0.25), b: rgb(0.35, 0.15, 0.45) };
pub(crate) const BLUE_CHECKER: Texture =
    Texture::Checker { period: 0.2, a: rgb(0.15, 0.30, 0.70), b: rgb(0.90, 0.85, 0.30) };
pub(crate) const PANELS: Texture = Texture::Panels { width: 0.12, height: 0.38 };

/// [`Backdrop::Room`]'s objects, 1 to 4 m behind the glass, so that views through the window have
/// strong parallax.
fn room_objects() -> Vec<Object> {
    let ht = HEIGHT;
    vec![
        sphere([-0.45, 0.45, -1.1], 0.45, RED_STRIPES),
        cuboid([0.45, 0.0, -2.1], [1.05, 0.8, -1.5], AMBER_NOISE),
        sphere([1.1, 1.35, -3.0], 0.55, BLUE_CHECKER),
        cuboid(
            [-1.45, 0.0, -2.8],
            [-1.05, ht, -2.4],
            Texture::Stripes { period: 0.1, a: rgb(0.90, 0.90, 0.90), b: rgb(0.25, 0.25, 0.30) },
        ),
        cuboid([-0.35, 0.0, -3.7], [0.35, 1.5, -3.35], PANELS),
    ]
}

/// [`Backdrop::Showcase`]'s display: a plinth the width of the window, and on it two balls, a
/// crate and a panelled column, 0.15 to 1.45 m behind the glass. Seen through a pane that fills
/// much of each view, they are easy to reconstruct; the camera room's reflection lies 3 to 8 m
/// behind the pane (its mirror image), so the two layers sit at very different depths.
fn showcase_objects() -> Vec<Object> {
    vec![
        cuboid(
            [-1.6, 0.0, -1.5],
            [1.6, 0.45, -0.1],
            Texture::Plain { colour: rgb(0.35, 0.30, 0.28), grain: 0.1 },
        ),
        sphere([-0.7, 0.75, -0.5], 0.3, RED_STRIPES),
        cuboid([0.2, 0.45, -1.0], [0.7, 0.95, -0.55], AMBER_NOISE),
        sphere([0.95, 0.8, -0.45], 0.3, BLUE_CHECKER),
        cuboid([-0.25, 0.45, -1.45], [0.05, 1.7, -1.2], PANELS),
    ]
}

/// A pane's frame bar or sill: a box (min, max corners in the pane's own frame) turned with the
/// pane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FrameBox {
    pub min: DVec3,
    pub max: DVec3,
    pub turn: Option<Turn>,
}

type Boxes = Vec<FrameBox>;

/// The rooms, objects, panes and frames in the local frame; also the frame boxes and each pane's
/// (width, height, R0).
fn build_world(config: &SyntheticConfig) -> (World, Boxes, Vec<(f64, f64, f64)>) {
    let mut objects = camera_room();
    let mut behind = behind_shell(config.backdrop.depth());
    behind.extend(match config.backdrop {
        Backdrop::Room => room_objects(),
        Backdrop::Showcase => showcase_objects(),
    });
    // The room behind the glass is lit more dimly, like a shop window seen from a bright room:
    // that is what makes real reflections stand out, and it keeps R0 = 0.2 clearly visible.
    let gain = config.behind_gain;
    objects.extend(behind.into_iter().map(|o| Object { gain, ..o }));
    objects.extend(light_panels(config.reflected_lights));

    let wall = pane_wall(&room_slots(config), config.r0, WALL_Y);
    objects.extend(wall.frame_boxes.iter().map(|&b| frame_object(b)));
    objects.push(wall_object(wall.holes));

    // A key light from above and a fill light from the window side, so that the surfaces facing
    // the glass (what it reflects) are lit as well as those seen through it.
    let lights = vec![
        (DVec3::new(-0.3, 1.0, 0.25).normalize(), 0.45),
        (DVec3::new(0.4, 0.3, -0.85).normalize(), 0.35),
    ];
    let world = World { objects, panes: wall.panes, lights, ambient: 0.45, seed: config.seed };
    (world, wall.frame_boxes, wall.sizes)
}

/// The camera room and what stands in it.
fn camera_room() -> Vec<Object> {
    let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
    let (hw, ht, fd) = (HALF_WIDTH, HEIGHT, FRONT_DEPTH);
    vec![
        // Camera room. Floor tiles, ceiling, side walls, and the poster wall behind the cameras.
        quad(
            [0.0, 0.0, 0.5 * fd],
            x,
            z,
            [hw, 0.5 * fd],
            Texture::Checker { period: 0.5, a: rgb(0.62, 0.50, 0.36), b: rgb(0.36, 0.25, 0.16) },
        ),
        quad(
            [0.0, ht, 0.5 * fd],
            x,
            z,
            [hw, 0.5 * fd],
            Texture::Plain { colour: rgb(0.80, 0.79, 0.75), grain: 0.08 },
        ),
        quad(
            [-hw, 0.5 * ht, 0.5 * fd],
            z,
            y,
            [0.5 * fd, 0.5 * ht],
            Texture::Stripes { period: 0.3, a: rgb(0.20, 0.50, 0.52), b: rgb(0.82, 0.80, 0.66) },
        ),
        quad(
            [hw, 0.5 * ht, 0.5 * fd],
            z,
            y,
            [0.5 * fd, 0.5 * ht],
            Texture::Noise { scale: 0.35, a: rgb(0.85, 0.55, 0.30), b: rgb(0.55, 0.16, 0.14) },
        ),
        quad(
            [0.0, 0.5 * ht, fd],
            x,
            y,
            [hw, 0.5 * ht],
            Texture::Panels { width: 0.55, height: 0.7 },
        ),
        // Camera side, near the wall: a bookshelf left of the window and a ball on a pedestal
        // right of it, both seen directly and, mirrored, in the glass from oblique views.
        cuboid([-2.7, 0.0, 0.15], [-1.9, 1.7, 0.6], Texture::Panels { width: 0.08, height: 0.28 }),
        cuboid(
            [1.7, 0.0, 0.25],
            [2.1, 0.9, 0.65],
            Texture::Stripes { period: 0.07, a: rgb(0.90, 0.88, 0.80), b: rgb(0.30, 0.28, 0.40) },
        ),
        sphere(
            [1.9, 1.2, 0.45],
            0.3,
            Texture::Checker { period: 0.12, a: rgb(0.95, 0.80, 0.15), b: rgb(0.15, 0.25, 0.65) },
        ),
        // The foreground plant that cuts the glass masks.
        cuboid(
            [0.29, 0.0, 0.87],
            [0.35, 0.95, 0.93],
            Texture::Plain { colour: rgb(0.30, 0.22, 0.15), grain: 0.1 },
        ),
        sphere(
            [0.32, 1.1, 0.9],
            0.2,
            Texture::Noise { scale: 0.05, a: rgb(0.55, 0.80, 0.25), b: rgb(0.10, 0.35, 0.12) },
        ),
    ]
}

/// The light panels on the wall behind the cameras: the first `count` of [`LIGHT_SPOTS`].
fn light_panels(count: usize) -> impl Iterator<Item = Object> {
    LIGHT_SPOTS.into_iter().take(count).map(|(lx, ly)| {
        let (hx, hy) = (LIGHT_HALF[0], LIGHT_HALF[1]);
        Object {
            shape: Shape::Cuboid {
                min: DVec3::new(lx - hx, ly - hy, FRONT_DEPTH - 0.04),
                max: DVec3::new(lx + hx, ly + hy, FRONT_DEPTH),
                turn: None,
            },
            texture: Texture::Plain { colour: rgb(1.0, 0.96, 0.88), grain: 0.0 },
            gain: LIGHT_GAIN,
        }
    })
}

/// The panes of the window wall, their frames and sills, the openings they leave in the wall
/// (x0, x1, y0, y1 about the wall's centre), and each pane's (width, height, R0).
pub(crate) struct PaneWall {
    pub panes: Vec<Pane>,
    pub frame_boxes: Boxes,
    pub holes: Vec<[f64; 4]>,
    pub sizes: Vec<(f64, f64, f64)>,
}

/// Where one pane sits in its wall and what it is: centre (x, y) in the wall, size, turn.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PaneSlot {
    pub kind: PaneKind,
    pub cx: f64,
    pub cy: f64,
    pub w: f64,
    pub h: f64,
    pub turn_deg: f64,
}

/// The room's panes: those of `config` side by side in the window wall, at [`PANE_Y`].
fn room_slots(config: &SyntheticConfig) -> Vec<PaneSlot> {
    let (single_w, pane_h) = config.backdrop.pane_size();
    let (single_w, pane_h) = if config.pane_scale == 1.0 {
        (single_w, pane_h)
    } else {
        let s = config.pane_scale;
        ((single_w * s).min(2.0 * HALF_WIDTH - 0.8), (pane_h * s).min(MAX_PANE_H))
    };
    let (w, xs) = pane_slots(config.panes.len(), single_w);
    config
        .panes
        .iter()
        .zip(xs)
        .enumerate()
        .map(|(k, (&kind, cx))| PaneSlot {
            kind,
            cx,
            cy: PANE_Y,
            w,
            h: pane_h,
            turn_deg: config.pane_turn_deg.get(k).copied().unwrap_or(0.0),
        })
        .collect()
}

/// The panes of `slots` in a wall whose centre is `wall_y` high, each in its frame (glass in an
/// opening with a sill under it, a mirror hung on the wall); `r0` overrides the materials'.
pub(crate) fn pane_wall(slots: &[PaneSlot], r0_override: Option<f64>, wall_y: f64) -> PaneWall {
    let mut wall = PaneWall {
        panes: Vec::new(),
        frame_boxes: Vec::new(),
        holes: Vec::new(),
        sizes: Vec::new(),
    };
    for &PaneSlot { kind, cx, cy, w, h: pane_h, turn_deg } in slots {
        let (x0, x1) = (cx - 0.5 * w, cx + 0.5 * w);
        let (y0, y1) = (cy - 0.5 * pane_h, cy + 0.5 * pane_h);
        let f = FRAME_W;
        // How far a turned frame's side edges leave the pane's centre line in z.
        let reach = (0.5 * w + f) * turn_deg.to_radians().sin().abs();
        let (pane_z, r0, frame_z) = match kind {
            // Glass sits in the middle of a frame that goes through the wall.
            PaneKind::Glass => (0.0, GLASS_R0, [-0.06, 0.04]),
            // A mirror hangs 1.5 cm in front of the wall in a shallow frame, further out when
            // it is turned, so that its edges clear the wall.
            PaneKind::Mirror => (0.015 + reach, MIRROR_R0, [reach, 0.05 + reach]),
        };
        let r0 = r0_override.unwrap_or(r0);
        let turn = (turn_deg != 0.0).then(|| Turn::about_y(DVec3::new(cx, cy, pane_z), turn_deg));
        let bars = [
            ([x0 - f, y0 - f], [x1 + f, y0]),
            ([x0 - f, y1], [x1 + f, y1 + f]),
            ([x0 - f, y0], [x0, y1]),
            ([x1, y0], [x1 + f, y1]),
        ];
        for (lo, hi) in bars {
            let (min, max) =
                (DVec3::new(lo[0], lo[1], frame_z[0]), DVec3::new(hi[0], hi[1], frame_z[1]));
            wall.frame_boxes.push(FrameBox { min, max, turn });
        }
        if kind == PaneKind::Glass {
            // The opening holds the frame, turned or not.
            let (h0, h1) = match turn {
                None => (x0 - f, x1 + f),
                Some(_) => {
                    let c = turn_deg.to_radians().cos().abs();
                    let half = (0.5 * w + f) * c + 0.06 * (1.0 - c * c).sqrt();
                    (cx - half, cx + half)
                }
            };
            wall.holes.push([h0, h1, y0 - f - wall_y, y1 + f - wall_y]);
            // A sill under the window, as in a real room; it sticks out towards the cameras.
            wall.frame_boxes.push(FrameBox {
                min: DVec3::new(h0 - 0.06, y0 - f - 0.05, -0.06),
                max: DVec3::new(h1 + 0.06, y0 - f, 0.14),
                turn: None,
            });
        }
        let rect = Rect {
            centre: DVec3::new(cx, cy, pane_z),
            u: turn.map_or(DVec3::X, |t| t.dir(DVec3::X)),
            v: DVec3::Y,
            half_u: 0.5 * w,
            half_v: 0.5 * pane_h,
        };
        wall.panes.push(Pane { rect, r0 });
        wall.sizes.push((w, pane_h, r0));
    }
    wall
}

/// A frame bar or sill as a traced object.
pub(crate) fn frame_object(FrameBox { min, max, turn }: FrameBox) -> Object {
    Object {
        shape: Shape::Cuboid { min, max, turn },
        texture: Texture::Noise { scale: 0.04, a: rgb(0.92, 0.92, 0.90), b: rgb(0.55, 0.52, 0.48) },
        gain: 1.0,
    }
}

/// The wall with the windows cut out (its front side faces the cameras).
fn wall_object(holes: Vec<[f64; 4]>) -> Object {
    Object {
        shape: Shape::Quad {
            rect: Rect {
                centre: DVec3::new(0.0, WALL_Y, 0.0),
                u: DVec3::X,
                v: DVec3::Y,
                half_u: HALF_WIDTH,
                half_v: 0.5 * HEIGHT,
            },
            holes,
        },
        texture: Texture::Noise { scale: 0.3, a: rgb(0.82, 0.82, 0.76), b: rgb(0.64, 0.69, 0.63) },
        gain: 1.0,
    }
}

pub(crate) fn layout(config: &SyntheticConfig) -> Layout {
    let (world, frame_boxes, sizes) = match config.setting {
        Setting::Room => build_world(config),
        Setting::Street => street::build_world(config),
    };
    let placement = Placement::fixed();
    let up = placement.rotation * DVec3::Y;
    let intrinsics = Intrinsics::from_fov_x(FOV_X_DEG.to_radians(), config.width, config.height);
    let paths: Vec<(DVec3, DVec3)> = match config.setting {
        Setting::Room => {
            let room = (0..config.room_views).map(|j| room_view_path(j, config.room_views));
            (0..config.views)
                .map(|i| camera_path(config.path, i, config.views))
                .chain(room)
                .collect()
        }
        Setting::Street => {
            (0..config.views).map(|i| street::camera_path(i, config.views)).collect()
        }
    };
    let cameras = paths
        .into_iter()
        .enumerate()
        .map(|(i, (eye, target))| {
            let pose =
                Pose::look_at(placement.point_to_world(eye), placement.point_to_world(target), up);
            Camera::new(format!("view_{i:03}.png"), intrinsics, pose)
        })
        .collect();
    let planes = world
        .panes
        .iter()
        .zip(&config.panes)
        .zip(sizes)
        .map(|((pane, &kind), (w, h, r0))| {
            let material = match kind {
                PaneKind::Glass => Material::Glass,
                PaneKind::Mirror => Material::Mirror,
            };
            let mut plane = ReflectionPlane::new(
                placement.point_to_world(pane.rect.centre),
                placement.rotation * pane.rect.normal(),
                placement.rotation * pane.rect.u,
                w,
                h,
                material,
            );
            plane.r0_logit = (r0 / (1.0 - r0)).ln();
            plane
        })
        .collect();
    Layout { world, placement, cameras, planes, frame_boxes, lens: config.lens.distortion() }
}

/// The local-frame ray through the continuous pixel position `(px, py)`.
pub(crate) fn local_ray(layout: &Layout, camera: &Camera, px: f64, py: f64) -> Ray {
    let pinhole = camera.intrinsics.unproject(px, py);
    // Through a lens the photo's pixel shows the direction whose distortion lands there.
    let dir = match layout.lens.and_then(|d| d.undistort(pinhole.x, pinhole.y)) {
        Some((x, y)) => DVec3::new(x, y, 1.0),
        None => pinhole,
    };
    let d = camera.pose.direction_to_world(dir);
    Ray::new(
        layout.placement.point_to_local(camera.pose.centre()),
        layout.placement.dir_to_local(d).normalize(),
    )
}

/// Project a world point into a camera: pixel position if it is in front and inside the image.
#[cfg(test)]
pub(crate) fn project(camera: &Camera, p: DVec3) -> Option<[f64; 2]> {
    project_through(None, camera, p)
}

/// [`project`] through a lens: the photo's pixel position of `p`.
pub(crate) fn project_through(
    lens: Option<Distortion>,
    camera: &Camera,
    p: DVec3,
) -> Option<[f64; 2]> {
    let q = camera.pose.transform_point(p);
    if q.z <= 1e-3 {
        return None;
    }
    let (x, y) = (q.x / q.z, q.y / q.z);
    let (x, y) = lens.map_or((x, y), |d| d.distort(x, y));
    let k = &camera.intrinsics;
    let (u, v) = (k.fx * x + k.cx, k.fy * y + k.cy);
    let inside = u >= 0.0 && v >= 0.0 && u < f64::from(k.width) && v < f64::from(k.height);
    inside.then_some([u, v])
}
