//! trgs-core: everything of TR-Gaussians that needs no GPU.
//!
//! - [`blocks`]: a capture split into overlapping blocks on the ground (partition and views);
//! - [`bake`]: a model with planes as plain Gaussians for other 3DGS viewers;
//! - [`scene`]: Gaussians (structure of arrays), cameras, reflection planes, input validation;
//! - [`plane_math`]: Householder reflections, ray-rectangle hits, nearest-plane selection, Schlick;
//! - [`plane_grad`]: a mirrored view's gradient chained into its plane's parameters;
//! - [`plane_carry`]: the Gaussians only a plane shows, moved with it so that their mirror images
//!   stay;
//! - [`fit`]: plane fitting for initialisation (RANSAC, minimum-area box, rectangle sampling);
//! - [`pipeline`]: what the GPU stages and their CPU twins share: tile grid, key layout,
//!   thresholds, reflection model, render settings, step guard, Adam's and the losses' settings;
//! - [`reference`]: the CPU reference renderer, stage by stage, forward and backward (f64);
//! - [`metrics`]: PSNR and SSIM as 3DGS evaluates them;
//! - [`io`]: COLMAP, transforms.json, glass masks, test split, planes.json and PLY.
//!
//! The procedural glass scenes that demos and tests train on are the crate `trgs-synthetic`.
pub mod bake;
pub mod blocks;
pub mod fit;
pub mod fixtures;
pub mod image;
pub mod io;
pub mod lens;
pub mod metrics;
pub mod parallel;
pub mod pipeline;
pub mod plane_carry;
pub mod plane_grad;
pub mod plane_math;
pub mod reference;
pub mod rng;
pub mod scene;
pub mod scratch;
pub mod sh;

pub use image::Image;
pub use scene::{
    Camera, Gaussians, Intrinsics, Material, Population, Pose, ReflectionPlane, ViewTransform,
};
