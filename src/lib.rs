//! trgs: TR-Gaussians (3D Gaussian Splatting with learnable reflection planes) in Rust.
//!
//! This facade re-exports the workspace crates so that an embedding app depends on one package:
//! - [`core`]: scene model, reflection-plane math, plane fitting, the CPU reference renderer and
//!   its gradients, image metrics and file formats (no GPU);
//! - [`render`]: the wgpu renderer;
//! - [`train`]: the optimisation.
pub use trgs_core as core;
pub use trgs_render as render;
pub use trgs_train as train;
