//! trgs-render: the TR-Gaussians renderer on wgpu. Device setup with optional features and their
//! fallbacks ([`GpuContext`]), the scene in GPU buffers ([`GpuScene`]), one module per WGSL stage
//! ([`stages`]), the forward [`Renderer::render`] that produces a [`Frame`] with every layer, and
//! [`Renderer::backward`] that turns dL/d(each layer) into the gradients of every Gaussian
//! attribute and every plane parameter.
//!
//! ```
//! use trgs_core::fixtures::{SceneSpec, random_scene};
//! use trgs_core::reference::FrameGrads;
//! use trgs_render::{
//!     BackwardOptions, GpuContext, GpuScene, Layer, LayerGrads, RenderOptions, Renderer,
//! };
//!
//! let ctx = GpuContext::new()?; // the best adapter (lavapipe when there is no GPU)
//! let scene = random_scene(&SceneSpec { planes: 1, ..SceneSpec::default() });
//! let gpu_scene = GpuScene::upload(&ctx, &scene.gaussians.cast::<f32>(), &scene.planes)?;
//! let renderer = Renderer::new(&ctx);
//! let mut frame = renderer.render(&gpu_scene, &scene.camera, &RenderOptions::default())?;
//! let color = frame.read_layer(&ctx, Layer::Color)?; // trgs_core::Image<f32>, RGB
//! let layers = frame.read_images(&ctx)?; // every layer, and each plane's C_raw and A
//!
//! // L = the sum of the final image: dL/dC = 1, every other layer 0.
//! let mut dl = FrameGrads::zeros(frame.width(), frame.height(), frame.plane_count());
//! dl.color.data.fill(1.0);
//! let upstream = LayerGrads::upload(&ctx, &frame, &dl)?; // checked: sizes, finite values
//! let grads = renderer.backward(&gpu_scene, &mut frame, &upstream, &BackwardOptions::default())?;
//! let per_gaussian = grads.gaussians.read(&ctx)?; // shaped like the scene's Gaussians
//! assert_eq!(per_gaussian.len(), scene.gaussians.len());
//! println!("dL/d(plane 0 centre) = {:?}", grads.planes[0].centre);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
mod backward;
mod device;
mod display;
mod frame;
pub mod gpu;
mod gpu_error;
mod kernels;
mod layer_grads;
pub mod layout;
mod renderer;
mod scene;
pub mod shader;
pub mod stages;

pub use backward::{BackwardError, BackwardOptions, Gradients};
pub use device::{
    BlockWidth, Capabilities, DeviceError, DeviceOptions, GpuContext, STORAGE_BUFFERS_PER_STAGE,
    TileLayout, device_descriptor, pick_adapter,
};
pub use display::{DisplayError, DisplayTarget, layer_mapping};
pub use frame::{
    DepthOrderIntermediates, Frame, FrameImages, Layer, LayerBuffers, PlaneImages, ViewBuffers,
    ViewIntermediates,
};
pub use gpu::KernelTime;
pub use gpu_error::GpuError;
pub use layer_grads::{LayerGrads, LayerGradsError};
pub use renderer::{RenderError, RenderOptions, Renderer};
pub use scene::{GpuScene, SceneGradBuffers, UploadError};
pub use trgs_core::reference::ReflectionModel;
