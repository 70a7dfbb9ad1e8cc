//! The CPU reference renderer: one module per GPU stage, named as the WGSL stage it mirrors
//! (`project`, `tile_counts`, `depth_order`, `prefix_sum`, `emit_keys`, `sort`, `tile_ranges`, `footprint`,
//! `rasterize`, `rasterize_reflection`, `compose`, `display`, and training's `exposure`) and its adjoint (`*_bwd`). It runs in f64 so
//! that its gradients can be checked against central finite differences, and it is the oracle of
//! every GPU stage.
//!
//! [`render`] runs the forward pipeline of docs/ARCHITECTURE.md ("Data flow") and keeps what the
//! backward needs; [`backward`] takes dL/d(each output layer) and returns dL/d(every Gaussian
//! attribute and every plane's centre, normal and R0 logit).
//!
//! What the twins and the GPU stages must agree on (the tile grid, the key layout, the
//! thresholds, the reflection model, the settings, the guard's bits, Adam's rates) is not defined
//! here but in [`crate::pipeline`], which both import.
mod adam;
mod backward;
mod block_reach;
mod compose;
mod compose_bwd;
mod depth_order;
mod display;
mod emit_keys;
mod exposure;
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

pub use adam::adam;
pub use backward::{BackwardOptions, SceneGrads, backward};
pub use block_reach::{block_reach, reaches_f32};
pub use compose::{ComposeOutput, compose};
pub use compose_bwd::{ComposeGrads, compose_bwd};
pub use depth_order::{depth_key, depth_order};
pub use display::{display, display_pixel, pack4x8unorm};
pub use emit_keys::emit_keys;
pub use exposure::{ExposureGrads, exposure, exposure_bwd, exposure_pixel};
pub use footprint::footprint;
pub use frame::{Frame, FrameGrads, PlaneLayerGrads, PlaneLayers, ViewPass};
pub use mcmc::{draw_below, mcmc_noise, mcmc_regularise, noise_normal, noise_offset, pcg_hash};
pub use photometric_loss::{PhotometricLoss, photometric_loss, photometric_loss_covered};
pub use prefix_sum::prefix_sum;
pub(crate) use project::sigmoid;
pub use project::{Projected, ProjectionFilter, project};
pub use project_bwd::{ProjectedGrads, project_bwd};
pub use rasterize::{PixelState, rasterize};
pub use rasterize_bwd::{RasterizeUpstream, rasterize_bwd};
pub use rasterize_reflection::{ReflectionPixelState, rasterize_reflection};
pub use rasterize_reflection_bwd::rasterize_reflection_bwd;
pub use regularisers::{
    LayerLoss, RegulariserInputs, Regularisers, depth_variance_loss, gradient_conflict_loss,
    mask_loss, regularisers,
};
pub use render::{render, render_view};
pub use sort::sort_keys;
pub use step_guard::step_guard;
pub use tile_counts::{tile_counts, tile_rect};
pub use tile_ranges::tile_ranges;
