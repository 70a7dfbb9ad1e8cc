//! trgs GPU renderer (wgpu). This crate holds the device layer; the WGSL stages and their Rust
//! drivers arrive with the GPU forward renderer, and every stage's CPU twin already lives in
//! `trgs_core::reference`.
pub mod device;

pub use device::{Capabilities, DeviceError, DeviceOptions, GpuContext};
pub use trgs_core as core;
