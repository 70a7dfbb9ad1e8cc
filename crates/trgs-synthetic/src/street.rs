//! The street fixture ([`Setting::Street`](super::Setting::Street)): a shop front 24 m long
//! with windows of glass and a mirror, the shops behind it, a street with lamp posts, and
//! across it facades that the glass reflects and that no camera faces; two walks past the
//! shops, one near and one across the road. Long enough that a split cuts it into blocks, with
//! panes across the seams of two and four blocks.
//!
//! Local frame as in the room (y up, the shop front in z = 0 facing +z): x runs along the
//! street, the shops lie at z < 0 and the street at z > 0.
use std::f64::consts::TAU;

use glam::DVec3;

use super::config::{PaneKind, SyntheticConfig};
use super::generate::{
    AMBER_NOISE, BLUE_CHECKER, FrameBox, PANELS, PaneSlot, RED_STRIPES, cuboid, frame_object,
    pane_wall, quad, rgb, sphere,
};
use super::geom::Rect;
use super::texture::Texture;
use super::trace::{Object, Shape, World};

/// Half the street's length: the shop front and the facades across run from -12 to 12 m.
const HALF_LENGTH: f64 = 12.0;
/// Depth of the shops behind the front, and their ceiling.
const SHOP_DEPTH: f64 = 3.5;
const SHOP_CEILING: f64 = 3.2;
/// Where the facades across the street stand, and the height of everything (the sky above).
const ACROSS_Z: f64 = 10.0;
const TOP: f64 = 8.0;
/// The pavement in front of the shops, then the road.
const PAVEMENT_Z: f64 = 2.5;

/// The shop windows left to right (centre x, width), all 1.9 m tall at 1.6 m, and the mirror
/// (a mirrored panel between two shops, slot 3); a config's panes take the first slots. Slot 2
/// spans x = 0 (the seam of two blocks), slot 1 reaches x = -5.5 (a seam of four).
const SLOTS: [(f64, f64); 5] = [(-8.6, 2.2), (-4.0, 3.0), (0.5, 3.2), (4.6, 1.2), (8.6, 2.4)];
const PANE_CY: f64 = 1.6;
const PANE_H: f64 = 1.9;
/// The shop front's centre height and half size.
const FRONT_CY: f64 = 0.5 * TOP;

/// Walls between the shops (x).
const PARTITIONS: [f64; 4] = [-6.4, -1.9, 3.6, 6.2];

/// The panes of `panes` in the street's slots.
fn slots(panes: &[PaneKind]) -> Vec<PaneSlot> {
    panes
        .iter()
        .zip(SLOTS)
        .map(|(&kind, (cx, w))| PaneSlot { kind, cx, cy: PANE_CY, w, h: PANE_H, turn_deg: 0.0 })
        .collect()
}

/// The street's world, its frame boxes and each pane's (width, height, R0).
pub(crate) fn build_world(
    config: &SyntheticConfig,
) -> (World, Vec<FrameBox>, Vec<(f64, f64, f64)>) {
    let mut objects = street_and_across();
    let gain = config.behind_gain;
    objects.extend(shops().into_iter().map(|o| Object { gain, ..o }));
    let wall = pane_wall(&slots(&config.panes), config.r0, FRONT_CY);
    objects.extend(wall.frame_boxes.iter().map(|&b| frame_object(b)));
    objects.push(Object {
        shape: Shape::Quad {
            rect: Rect {
                centre: DVec3::new(0.0, FRONT_CY, 0.0),
                u: DVec3::X,
                v: DVec3::Y,
                half_u: HALF_LENGTH,
                half_v: 0.5 * TOP,
            },
            holes: wall.holes,
        },
        texture: Texture::Panels { width: 0.9, height: 0.6 },
        gain: 1.0,
    });
    // Daylight: the sun high and a little behind the shop front, and the sky's fill from across
    // the street, so that the facades the glass reflects are as bright as the front.
    let lights = vec![
        (DVec3::new(-0.3, 1.0, 0.35).normalize(), 0.5),
        (DVec3::new(0.3, 0.4, -0.85).normalize(), 0.35),
    ];
    let world = World { objects, panes: wall.panes, lights, ambient: 0.45, seed: config.seed };
    (world, wall.frame_boxes, wall.sizes)
}

/// The street in front of the shops: pavement and road, lamp posts, a bench and a planter; the
/// facades across (four houses and a kiosk before them), the street's ends and the sky.
fn street_and_across() -> Vec<Object> {
    let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
    let hl = HALF_LENGTH;
    let road = ACROSS_Z - PAVEMENT_Z;
    let mut objects = vec![
        quad(
            [0.0, 0.0, 0.5 * PAVEMENT_Z],
            x,
            z,
            [hl, 0.5 * PAVEMENT_Z],
            Texture::Checker { period: 0.4, a: rgb(0.78, 0.76, 0.72), b: rgb(0.58, 0.57, 0.55) },
        ),
        quad(
            [0.0, 0.0, PAVEMENT_Z + 0.5 * road],
            x,
            z,
            [hl, 0.5 * road],
            Texture::Noise { scale: 0.2, a: rgb(0.30, 0.30, 0.32), b: rgb(0.18, 0.18, 0.20) },
        ),
        quad(
            [0.0, TOP, 0.5 * (ACROSS_Z - SHOP_DEPTH)],
            x,
            z,
            [hl, 0.5 * (ACROSS_Z + SHOP_DEPTH)],
            Texture::Plain { colour: rgb(0.62, 0.78, 0.95), grain: 0.05 },
        ),
    ];
    for side in [-1.0, 1.0] {
        objects.push(quad(
            [side * hl, 0.5 * TOP, 0.5 * ACROSS_Z],
            z,
            y,
            [0.5 * ACROSS_Z, 0.5 * TOP],
            Texture::Bricks {
                width: 0.25,
                height: 0.08,
                brick: rgb(0.55, 0.50, 0.62),
                mortar: rgb(0.80, 0.78, 0.74),
            },
        ));
    }
    // Four houses across the street, each a face of its own: what the glass reflects.
    let houses = [
        Texture::Bricks {
            width: 0.3,
            height: 0.1,
            brick: rgb(0.70, 0.32, 0.20),
            mortar: rgb(0.80, 0.78, 0.72),
        },
        Texture::Panels { width: 0.7, height: 1.1 },
        Texture::Stripes { period: 0.5, a: rgb(0.90, 0.85, 0.55), b: rgb(0.35, 0.55, 0.60) },
        Texture::Checker { period: 0.6, a: rgb(0.85, 0.85, 0.88), b: rgb(0.30, 0.40, 0.65) },
    ];
    let house_w = 2.0 * hl / houses.len() as f64;
    for (k, texture) in houses.into_iter().enumerate() {
        let cx = -hl + (k as f64 + 0.5) * house_w;
        objects.push(quad([cx, 0.5 * TOP, ACROSS_Z], x, y, [0.5 * house_w, 0.5 * TOP], texture));
    }
    objects.push(cuboid([-2.5, 0.0, 8.6], [-0.5, 2.4, 9.6], AMBER_NOISE));
    objects.push(sphere([5.5, 1.2, 9.0], 0.8, RED_STRIPES));
    // On the pavement: lamp posts, a bench and a planter, which cut the masks of some views.
    for px in [-6.4, 2.6, 9.9] {
        objects.push(cuboid(
            [px - 0.06, 0.0, 1.7],
            [px + 0.06, 3.6, 1.82],
            Texture::Plain { colour: rgb(0.15, 0.17, 0.16), grain: 0.05 },
        ));
    }
    objects.push(cuboid(
        [-1.6, 0.0, 1.3],
        [-0.2, 0.45, 1.7],
        Texture::Stripes { period: 0.07, a: rgb(0.55, 0.35, 0.20), b: rgb(0.35, 0.20, 0.10) },
    ));
    objects.push(sphere(
        [6.4, 0.45, 1.4],
        0.45,
        Texture::Noise { scale: 0.05, a: rgb(0.55, 0.80, 0.25), b: rgb(0.10, 0.35, 0.12) },
    ));
    objects
}

/// The shops behind the front: floor, ceiling, back wall, the walls between them and what each
/// window shows.
fn shops() -> Vec<Object> {
    let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
    let (hl, d, c) = (HALF_LENGTH, SHOP_DEPTH, SHOP_CEILING);
    let mut objects = vec![
        quad(
            [0.0, 0.0, -0.5 * d],
            x,
            z,
            [hl, 0.5 * d],
            Texture::Checker { period: 0.35, a: rgb(0.85, 0.85, 0.82), b: rgb(0.18, 0.20, 0.24) },
        ),
        quad(
            [0.0, c, -0.5 * d],
            x,
            z,
            [hl, 0.5 * d],
            Texture::Plain { colour: rgb(0.85, 0.85, 0.88), grain: 0.1 },
        ),
        quad(
            [0.0, 0.5 * c, -d],
            x,
            y,
            [hl, 0.5 * c],
            Texture::Stripes { period: 0.4, a: rgb(0.78, 0.62, 0.75), b: rgb(0.45, 0.30, 0.55) },
        ),
    ];
    for px in PARTITIONS {
        objects.push(quad(
            [px, 0.5 * c, -0.5 * d],
            z,
            y,
            [0.5 * d, 0.5 * c],
            Texture::Noise { scale: 0.25, a: rgb(0.75, 0.80, 0.45), b: rgb(0.30, 0.45, 0.25) },
        ));
    }
    objects.extend([
        sphere([-8.9, 0.45, -1.2], 0.45, RED_STRIPES),
        cuboid([-8.0, 0.0, -2.3], [-7.3, 1.1, -1.6], AMBER_NOISE),
        cuboid(
            [-5.3, 0.0, -1.6],
            [-2.7, 0.5, -0.6],
            Texture::Plain { colour: rgb(0.35, 0.30, 0.28), grain: 0.1 },
        ),
        sphere([-4.6, 0.8, -1.1], 0.3, BLUE_CHECKER),
        cuboid([-3.5, 0.0, -2.9], [-3.1, 2.1, -2.5], PANELS),
        sphere([0.0, 0.6, -1.9], 0.6, AMBER_NOISE),
        cuboid([1.0, 0.0, -1.3], [1.8, 1.3, -0.7], RED_STRIPES),
        cuboid(
            [-1.3, 0.0, -3.1],
            [-0.9, 2.6, -2.7],
            Texture::Stripes { period: 0.1, a: rgb(0.90, 0.90, 0.90), b: rgb(0.25, 0.25, 0.30) },
        ),
        cuboid([7.6, 0.0, -1.5], [8.4, 0.9, -0.8], BLUE_CHECKER),
        sphere([9.4, 1.0, -2.2], 0.5, RED_STRIPES),
    ]);
    objects
}

/// Eye and target of view `i` of `n`: the first half walks the pavement 3.2 m from the shop
/// front, left to right, turning from looking ahead to looking back; the second half walks back
/// across the road, 5.2 m from it, a little lower.
pub(crate) fn camera_path(i: usize, n: usize) -> (DVec3, DVec3) {
    let near = n.div_ceil(2);
    if i < near {
        let s = i as f64 / (near.max(2) - 1) as f64;
        let x = -10.5 + 21.0 * s;
        let eye = DVec3::new(x, 1.6 + 0.05 * (4.0 * TAU * s).sin(), 3.2);
        (eye, DVec3::new(x + 2.2 * (5.0 * TAU * s).sin(), 1.4, -1.0))
    } else {
        let s = (i - near) as f64 / ((n - near).max(2) - 1) as f64;
        let x = 10.5 - 21.0 * s;
        let eye = DVec3::new(x, 1.4 + 0.1 * (3.0 * TAU * s).sin(), 5.2);
        (eye, DVec3::new(x - 2.5 * (4.0 * TAU * s + 1.0).sin(), 1.5, -1.0))
    }
}
