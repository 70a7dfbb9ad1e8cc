#![doc = include_str!("../README.md")]
//!
//! The crates behind this facade: [`core`] (scene model, reflection-plane math, plane fitting,
//! the CPU reference renderer and its gradients, metrics, formats; no GPU), [`render`] (the wgpu
//! renderer and its kernel toolkit), [`train`] (a whole run, the training step, losses and
//! densification) and [`synthetic`] (the procedural glass scenes demos and tests train on). The
//! README's example above runs as this crate's doc test.
pub use trgs_core as core;
pub use trgs_render as render;
pub use trgs_synthetic as synthetic;
pub use trgs_train as train;
