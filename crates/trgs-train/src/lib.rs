//! trgs-train: optimisation of TR-Gaussians models, and the command-line tools around it (`train`,
//! `render`, `bench`). So far: the GPU Adam step ([`adam`]), and the model loading and output
//! helpers the tools share; the training loop arrives with the training milestone.
pub mod adam;
pub mod exr_layers;
pub mod model;
pub use trgs_core as core;
