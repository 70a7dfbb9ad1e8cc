//! trgs GPU renderer (wgpu). The WGSL stages and their Rust drivers arrive with the GPU forward
//! renderer; every stage's CPU twin already lives in `trgs_core::reference`.
pub use trgs_core as core;
