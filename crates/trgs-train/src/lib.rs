//! trgs-train: optimisation of TR-Gaussians models, and the command-line tools around it (`train`,
//! `render`, `bench`). The optimiser arrives with the training milestone; this crate holds the
//! model loading and output helpers the tools share.
pub mod exr_layers;
pub mod model;
pub use trgs_core as core;
