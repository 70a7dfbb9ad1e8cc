//! The pipeline's shared definitions: what the GPU stages (trgs-render, trgs-train) and their CPU
//! twins ([`crate::reference`]) must agree on, defined once so that neither side copies the
//! other's. The tile grid and tile rectangles, the depth keys' layout, the splatting thresholds,
//! the reflection model's switches, the display mapping, the render settings and their check, the
//! step guard's bits, Adam's settings and rates, and the loss and MCMC constants.
//!
//! Named `pipeline` because these specify the stages of docs/ARCHITECTURE.md ("Data flow")
//! themselves rather than either implementation of them: the GPU code imports them from here
//! as the twins do, and the twins' computations (`project`, `rasterize`, `compose`, `adam`,
//! `depth_key`, ...) stay in [`crate::reference`], the test oracle.
mod adam;
mod display;
mod exposure;
mod guard;
mod keys;
mod losses;
mod mcmc;
mod reflection;
mod settings;
mod splat;
mod tiles;

pub use adam::{AdamRate, AdamSettings};
pub use display::DisplayMapping;
pub use exposure::{EXPOSURE_IDENTITY, ExposureMatrix};
pub use guard::{GUARD_KEYS_DROPPED, GUARD_LOSS_NOT_FINITE};
pub use keys::{DEPTH_KEY_BITS, DEPTH_KEY_FLOOR, depth_key_base};
pub use losses::{DSSIM_LAMBDA, RegulariserWeights};
pub use mcmc::{MAX_REGULARISED_LOG_SCALE, NOISE_GATE_STEEPNESS, NOISE_GATE_THRESHOLD};
pub use reflection::ReflectionModel;
pub use settings::{RenderSettings, check_render_settings};
pub use splat::{COV2D_BLUR, GUARD_BAND, MAX_ALPHA, MIN_ALPHA, MIN_TRANSMITTANCE};
pub use tiles::{TILE_PIXELS, TILE_SIZE, TileGrid, TileRect};
