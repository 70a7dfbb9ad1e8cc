//! The kernel toolkit: what the renderer's stages are made of, and what trgs-train makes its
//! own GPU stages of. An app that renders and reads its layers back does not need it; one that
//! keeps the layers on the GPU reaches their buffers through [`FrameStages::layer_buffers`].
//!
//! - [`gpu`]: buffers ([`storage`], [`storage_init`], parameter blocks by [`params`]), binding
//!   ranges under the adapter's limits ([`range`]), dispatch grids ([`grid_1d`]), a
//!   [`Recorder`] of labelled and optionally timed passes, blocking readback ([`read_buffer`])
//!   with a wait limit, and GPU failures as errors ([`scoped`], [`ErrorScopes`]);
//! - [`shader`]: the WGSL sources under `shaders/` (compiled in by the build script) and their
//!   preprocessor; [`layout`]: the GPU structs and constants, declared once in Rust with their
//!   WGSL generated;
//! - [`paged`]: per-Gaussian arrays in pages of one binding each (a view's projected records
//!   and their gradients, which the rasterize passes bind whole);
//! - [`registry`]: the one table per crate that registers each kernel (its WGSL file and its
//!   defines per device), and the renderer's own tables ([`RENDER_KERNELS`],
//!   [`BENCH_KERNELS`]);
//! - [`FrameStages`] and [`GradientStages`]: the buffers and intermediate results of a
//!   frame's stages, for kernels that continue from them (the training losses, densification
//!   statistics) and for the tests that check each stage against its CPU twin.
pub mod gpu;
pub mod layout;
pub mod paged;
pub mod registry;
pub mod shader;

pub use crate::frame::{DepthOrderIntermediates, LayerBuffers, ViewBuffers, ViewIntermediates};
pub use crate::kernels::{BENCH_KERNELS, BenchKernelSpecs, BenchKernels, RENDER_KERNELS};
pub use crate::kernels::{Kernels as RenderKernels, RenderKernelSpecs};
pub use crate::stages::prefix_sum::PrefixSum;
pub use gpu::{
    BufferPool, ErrorScopes, GPU_WAIT_LIMIT, Kernel, KernelTime, PendingRead, Recorder, WAIT_SLICE,
    gpu_wait_limit, grid_1d, map_and_read, params, range, read_buffer, scoped, spread_block,
    spread_step, storage, storage_init, wait_for_gpu,
};
pub use registry::{KernelSpec, every_capability_set};

use crate::layout::{PROJECTED_GRAD_FLOATS, ProjectedGaussian, RasterState};
use crate::{GpuContext, GpuError};

/// The buffers and intermediate results of a rendered frame's stages.
pub trait FrameStages {
    /// The views: 0 is the camera, then one per mirrored pass.
    fn views(&self) -> &[ViewBuffers];

    /// The layer buffers (for the backward pass and kernels that read the layers in place).
    fn layer_buffers(&self) -> Option<&LayerBuffers>;

    /// Pass 1's per-pixel states.
    fn read_states(&self, ctx: &GpuContext) -> Result<Vec<RasterState>, GpuError>;

    /// The projected Gaussians of view `vi` (0 = camera, then mirrored passes).
    fn read_projected(
        &self,
        ctx: &GpuContext,
        vi: usize,
    ) -> Result<Option<Vec<ProjectedGaussian>>, GpuError>;

    /// The geometry stages' results of view `vi` (0 = camera, then mirrored passes) in the
    /// twin's form of one view alone (a frame rendered with `capture_intermediates`).
    fn read_intermediates(
        &self,
        ctx: &GpuContext,
        vi: usize,
        gaussians: usize,
    ) -> Result<Option<ViewIntermediates>, GpuError>;

    /// The frame's depth order, every view's together.
    fn read_depth_order(
        &self,
        ctx: &GpuContext,
    ) -> Result<Option<DepthOrderIntermediates>, GpuError>;
}

/// The buffers of a backward pass's stages.
pub trait GradientStages {
    /// Screen-space gradients of view `vi`: per Gaussian (dmean2d.xy, dopacity, ddepth,
    /// dconic a b c, dmask, dcolour rgb, dreflection).
    fn read_projected_grads(
        &self,
        ctx: &GpuContext,
        vi: usize,
    ) -> Result<Option<Vec<[f32; PROJECTED_GRAD_FLOATS as usize]>>, GpuError>;

    /// The pages of view `vi`'s screen-space gradients (`PROJECTED_GRAD_FLOATS` per Gaussian),
    /// for kernels that read them where they are.
    fn projected_grads(&self, vi: usize) -> Option<&paged::Paged>;
}
