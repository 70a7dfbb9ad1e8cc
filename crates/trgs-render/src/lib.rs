//! trgs-render: the TR-Gaussians renderer on wgpu. Device setup with optional features and their
//! fallbacks ([`GpuContext`]), the scene in GPU buffers ([`GpuScene`]), one module per WGSL stage
//! ([`stages`]) and the forward [`Renderer`] that produces a [`Frame`] with every layer.
//!
//! ```no_run
//! use trgs_core::fixtures::{SceneSpec, random_scene};
//! use trgs_render::{GpuContext, GpuScene, Layer, RenderOptions, Renderer};
//!
//! let ctx = GpuContext::new()?;
//! let scene = random_scene(&SceneSpec { planes: 1, ..SceneSpec::default() });
//! let gpu_scene = GpuScene::upload(&ctx, &scene.gaussians.cast::<f32>(), &scene.planes)?;
//! let renderer = Renderer::new(&ctx);
//! let frame = renderer.render(&gpu_scene, &scene.camera, &RenderOptions::default())?;
//! let color = frame.read_layer(&ctx, Layer::Color); // trgs_core::Image<f32>, RGB
//! let layers = frame.read_images(&ctx); // every layer, and each plane's C_raw and A
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
mod backward;
mod device;
mod frame;
pub mod gpu;
mod kernels;
mod layer_grads;
pub mod layout;
mod renderer;
mod scene;
pub mod shader;
pub mod stages;

pub use backward::{BackwardError, BackwardOptions, Gradients};
pub use device::{Capabilities, DeviceError, DeviceOptions, GpuContext};
pub use frame::{
    Frame, FrameImages, Layer, LayerBuffers, PlaneImages, ViewBuffers, ViewIntermediates,
};
pub use layer_grads::{LayerGrads, LayerGradsError};
pub use renderer::{RenderError, RenderOptions, Renderer};
pub use scene::{GpuScene, SceneGradBuffers};
