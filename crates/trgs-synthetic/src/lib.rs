//! The procedural glass scene: the built-in demo of `train` and the quality fixture of trgs.
//!
//! A room (6 m wide, 2.8 m high, 5 m deep) whose far wall holds one or more framed panes; behind
//! the wall lies a second room (4.5 m deep; 1.6 m for the showcase), seen only through the glass.
//! In the scene's local frame (y up, metres) the pane wall is z = 0 and the panes face +z, towards
//! the cameras:
//!
//! - behind the glass (transmission): a checkered floor, a brick back wall, two textured spheres,
//!   a noise-textured crate, a striped column and a shelf of coloured panels, at 1 to 4.5 m behind
//!   the pane, so that views through the glass have strong parallax ([`Backdrop::Room`], the
//!   default); or, with [`Backdrop::Showcase`], a display 1.6 m deep behind a larger pane: a
//!   plinth with two balls, a crate and a panelled column 0.15 to 1.45 m behind the glass;
//! - on the camera side (reflection): a bookshelf of coloured spines left of the window, a
//!   checkered ball on a striped pedestal right of it, a striped left wall, a noise-textured right
//!   wall, a poster wall behind the cameras, a tiled floor. These are seen directly near the
//!   window and, mirrored, in the glass; the poster wall (only ever seen in reflection) keeps the
//!   reflection clearly textured in frontal views;
//! - a foreground "plant" (a green ball on a pole) 0.9 m in front of the glass that covers part
//!   of the pane in some views, so that the glass masks have holes;
//! - an opaque frame (7 cm wide, 10 cm deep) around each glass pane and a sill below it, whose
//!   points give the plane initialisation its plane: the frame is coplanar with the wall.
//!
//! Mirrors hang on the wall (no hole) inside a shallow frame: what they transmit is the wall.
//! Panes are laid out side by side, centred; one pane is 1.6 m x 1.0 m (2.4 m x 1.4 m
//! for the showcase), more are narrower.
//!
//! Cameras follow (by default, see [`CameraPath`] for the others) a closed loop 2.3 to 2.9 m from the wall, up to about 52 degrees off the pane
//! normal, between 0.9 and 1.7 m high, all looking at a point 0.8 m behind the glass; every 8th
//! view of the loop is a test view. A few more training views stand near the window and look back
//! into the camera room, as a walk-through capture would: they reconstruct what the glass
//! reflects (the poster wall is otherwise seen only in reflection), which TR-Gaussians renders
//! from its primary Gaussians mirrored, while plain 3DGS has to fake the reflection behind the
//! glass. The whole scene is then placed in the world by a fixed rigid motion that
//! is not axis-aligned (world "up" is roughly -y, as in many COLMAP reconstructions), so that no
//! consumer can get away with assuming axis-aligned planes.
//!
//! Images are rendered by an independent ray tracer (`trace.rs`, `geom.rs`) with 2x2
//! supersampling; see `trace.rs` for the image model, which is trgs's compositing with the truth's
//! planes.
mod config;
pub mod family;
mod generate;
mod geom;
mod paths;
mod plan;
mod points;
mod render_views;
mod room;
mod street;
mod texture;
mod trace;
mod write;

pub use config::{
    Backdrop, CameraPath, DAY_BEHIND_GAIN, GLASS_R0, MIRROR_R0, NIGHT_BEHIND_GAIN, PaneKind,
    Setting, SyntheticConfig, SyntheticLens,
};
pub use plan::{SyntheticScene, TRACED_LONG_SIDE, generate};
pub use write::{colmap_model, write_dataset, write_generated};

#[cfg(test)]
mod tests;
