//! Camera paths in the scene's local frame: the views in front of the pane wall
//! ([`CameraPath`]) and the room views that look back into the camera room.
use std::f64::consts::{PI, TAU};

use glam::DVec3;

use super::config::CameraPath;
use super::room::FRONT_DEPTH;

/// Eye and target of view `i` of `n` along `path`, in the local frame.
pub(crate) fn camera_path(path: CameraPath, i: usize, n: usize) -> (DVec3, DVec3) {
    let s = i as f64 / n as f64;
    match path {
        CameraPath::Loop => camera_loop(i, n),
        CameraPath::Arc => {
            let theta = (-45.0 + 90.0 * s).to_radians();
            let eye = DVec3::new(2.7 * theta.sin(), 1.4, 2.7 * theta.cos());
            (eye, DVec3::new(0.25 * theta.sin(), 1.15, -0.8))
        }
        CameraPath::WalkBy => {
            let eye = DVec3::new(-2.2 + 4.4 * s, 1.55 + 0.03 * (6.0 * TAU * s).sin(), 2.2);
            (eye, DVec3::new(0.5 * eye.x, 1.15, -0.8))
        }
        CameraPath::CloseUp => {
            let theta = 0.5 * (TAU * s).sin();
            let r = 1.75 + 0.15 * (2.0 * TAU * s).cos();
            let eye = DVec3::new(
                r * theta.sin(),
                1.25 + 0.2 * (3.0 * TAU * s + 0.5).sin(),
                r * theta.cos(),
            );
            (eye, DVec3::new(0.2 * (TAU * s + 0.8).sin(), 1.2, -0.8))
        }
    }
}

/// The default camera loop: eye and target of view `i` of `n`.
fn camera_loop(i: usize, n: usize) -> (DVec3, DVec3) {
    let s = i as f64 / n as f64;
    // One sweep left-right per loop, three height oscillations: the loop covers a band of
    // positions instead of retracing one curve.
    let theta = 0.9 * (TAU * s).sin();
    let r = 2.6 + 0.3 * (2.0 * TAU * s).cos();
    let eye = DVec3::new(r * theta.sin(), 1.3 + 0.4 * (3.0 * TAU * s + 0.5).sin(), r * theta.cos());
    let target = DVec3::new(0.3 * (TAU * s + 0.8).sin(), 1.1 + 0.1 * (2.0 * TAU * s).sin(), -0.8);
    (eye, target)
}

/// Room view `j` of `n`: an eye near the window looking back into the camera room, the targets
/// sweeping the poster wall and the side walls from left to right.
pub(crate) fn room_view_path(j: usize, n: usize) -> (DVec3, DVec3) {
    let s = (j as f64 + 0.5) / n as f64;
    let eye = DVec3::new(-1.2 + 2.4 * s, 1.35 + 0.2 * (TAU * s).sin(), 0.8 + 0.4 * (PI * s).sin());
    let target = DVec3::new(-3.0 + 6.0 * s, 1.3, FRONT_DEPTH - 0.5);
    (eye, target)
}
