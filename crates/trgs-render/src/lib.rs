//! trgs-render: the TR-Gaussians renderer on wgpu.
//!
//! - [`GpuContext`]: the device, with its optional features and their fallbacks
//!   ([`DeviceOptions`], [`Capabilities`]); [`GpuContext::from_device`] shares a device an app
//!   made itself (from [`device_descriptor`]);
//! - [`GpuScene`]: Gaussians and reflection planes uploaded and validated;
//! - [`Renderer::render`]: a [`Frame`] with every [`Layer`] (final image, transmission,
//!   reflection, strength, mask, depth, alpha), read back with [`Frame::read_layer`] or kept on
//!   the GPU;
//! - [`Renderer::backward`]: dL/d(each layer) ([`LayerGrads`]) to the [`Gradients`] of every
//!   Gaussian attribute and every plane's centre, normal and R0;
//! - [`Renderer::display`] into a [`DisplayTarget`]: a layer as 8-bit RGBA in a texture, for
//!   windows;
//! - [`GpuError`]: out of memory, a lost device or a hung kernel, as the error of the call that
//!   met it.
//!
//! The stages themselves (one module per WGSL file, checked against its CPU twin in
//! `trgs_core::reference`) are internal; [`toolkit`] is what they are built from, and what
//! trgs-train builds its own stages from.
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
//! let planes = grads.planes.read(&ctx)?; // read back now; the backward did not wait
//! println!("dL/d(plane 0 centre) = {:?}", planes[0].centre);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
mod backward;
mod device;
mod display;
mod frame;
mod gpu_error;
mod kernels;
mod layer_grads;
mod renderer;
mod scene;
mod stages;
pub mod toolkit;

// Short paths to the toolkit inside the crate.
pub(crate) use toolkit::{gpu, layout};

pub use backward::{BackwardError, BackwardOptions, Gradients, PlaneGradsRead};
pub use device::{
    BlockWidth, Capabilities, DeviceError, DeviceOptions, GpuContext, STORAGE_BUFFERS_PER_STAGE,
    TileLayout, device_descriptor, pick_adapter,
};
pub use display::{DisplayError, DisplayTarget, layer_mapping};
pub use frame::{Frame, FrameImages, KeySizing, KeyTotals, Layer, PendingKeyTotals, PlaneImages};
pub use gpu_error::GpuError;
pub use layer_grads::{LayerGrads, LayerGradsError};
pub use renderer::{RenderError, RenderOptions, Renderer};
pub use scene::{GpuScene, SceneGradBuffers, UploadError};
pub use toolkit::KernelTime;
pub use trgs_core::pipeline::ReflectionModel;
