//! The CPU reference renderer: one module per GPU stage, named as the WGSL stage it mirrors
//! (`project`, `tile_counts`, `depth_order`, `prefix_sum`, `emit_keys`, `sort`, `tile_ranges`, `footprint`,
//! `rasterize`, `rasterize_reflection`, `compose`, `display`) and its adjoint (`*_bwd`). It runs in f64 so
//! that its gradients can be checked against central finite differences, and it is the oracle of
//! every GPU stage.
//!
//! [`render`] runs the forward pipeline of docs/ARCHITECTURE.md ("Data flow") and keeps what the
//! backward needs; [`backward`] takes dL/d(each output layer) and returns dL/d(every Gaussian
//! attribute and every plane's centre, normal and R0 logit).
mod adam;
mod backward;
mod block_reach;
mod compose;
mod compose_bwd;
mod depth_order;
mod display;
mod emit_keys;
mod footprint;
mod frame;
mod mcmc;
mod photometric_loss;
mod prefix_sum;
mod project;
mod project_bwd;
mod rasterize;
mod rasterize_bwd;
mod rasterize_reflection;
mod rasterize_reflection_bwd;
mod regularisers;
mod render;
mod sort;
mod step_guard;
mod tile_counts;
mod tile_ranges;

pub use adam::{AdamRate, AdamSettings, adam};
pub use backward::{
    BackwardOptions, PlaneGrad, SceneGrads, backward, mirrored_view_bwd, plane_grad,
};
pub use block_reach::{block_reach, reaches_f32};
pub use compose::{ComposeOutput, ReflectionModel, compose};
pub use compose_bwd::{ComposeGrads, compose_bwd};
pub use depth_order::{DEPTH_KEY_BITS, DEPTH_KEY_FLOOR, depth_key, depth_key_base, depth_order};
pub use display::{DisplayMapping, display, display_pixel, pack4x8unorm};
pub use emit_keys::emit_keys;
pub use footprint::{TileRect, footprint};
pub use frame::{Frame, FrameGrads, PlaneLayerGrads, PlaneLayers};
pub use mcmc::{
    MAX_REGULARISED_LOG_SCALE, NOISE_GATE_STEEPNESS, NOISE_GATE_THRESHOLD, draw_below, mcmc_noise,
    mcmc_regularise, noise_normal, noise_offset, pcg_hash,
};
pub use photometric_loss::{
    DSSIM_LAMBDA, PhotometricLoss, photometric_loss, photometric_loss_covered,
};
pub use prefix_sum::prefix_sum;
pub use project::{Projected, ProjectionFilter, project};
pub use project_bwd::{ProjectedGrads, ViewGrads, project_bwd};
pub use rasterize::{PixelState, rasterize};
pub use rasterize_bwd::{RasterizeUpstream, rasterize_bwd};
pub use rasterize_reflection::{ReflectionPixelState, rasterize_reflection};
pub use rasterize_reflection_bwd::rasterize_reflection_bwd;
pub use regularisers::{
    LayerLoss, RegulariserInputs, RegulariserWeights, Regularisers, depth_variance_loss,
    gradient_conflict_loss, mask_loss, regularisers,
};
pub use render::{RenderSettings, ViewPass, check_render_settings, render, render_view};
pub use sort::sort_keys;
pub use step_guard::{GUARD_KEYS_DROPPED, GUARD_LOSS_NOT_FINITE, step_guard};
pub use tile_counts::{TileGrid, tile_counts, tile_rect};
pub use tile_ranges::tile_ranges;

/// Side of a square screen tile in pixels. 8 rather than 3DGS's 16: a tile's list holds the
/// Gaussians that overlap it, so smaller tiles about halve the evaluations per pixel (and the
/// rasterize time of `bench`) for about 1.5x the keys, and a plane's footprint follows its
/// outline more closely.
pub const TILE_SIZE: u32 = 8;
/// Pixels per tile: the rasterizers' workgroup size and batch length.
pub const TILE_PIXELS: u32 = TILE_SIZE * TILE_SIZE;
/// Added to the diagonal of every 2D covariance (px^2): EWA's low-pass filter as in 3DGS.
pub const COV2D_BLUR: f64 = 0.3;
/// Upper bound on a Gaussian's alpha; keeps `1 - alpha` away from zero for the backward replay.
pub const MAX_ALPHA: f64 = 0.99;
/// Contributions with alpha below this are skipped (they cannot change an 8-bit pixel).
pub const MIN_ALPHA: f64 = 1.0 / 255.0;
/// A Gaussian that would bring a transmittance below this is not blended, and that chain stops.
pub const MIN_TRANSMITTANCE: f64 = 1e-4;
/// The Jacobian of the projection is evaluated with the mean clamped to this guard band around
/// the image (as a fraction of its size on each side): 3DGS's 1.3 x tan(fov / 2).
pub const GUARD_BAND: f64 = 0.15;
