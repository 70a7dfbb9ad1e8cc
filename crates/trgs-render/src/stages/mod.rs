//! One module per WGSL stage, named as the shader and as the CPU twin in
//! `trgs_core::reference`. Each records its dispatches into a [`crate::gpu::Recorder`].
pub mod compose;
pub mod compose_bwd;
pub mod depth_order;
pub mod display;
pub mod emit_keys;
pub mod prefix_sum;
pub mod project;
pub mod project_bwd;
pub mod rasterize;
pub mod rasterize_bwd;
pub mod rasterize_reflection;
pub mod rasterize_reflection_bwd;
pub mod sort;
pub mod tile_counts;
pub mod tile_ranges;

use crate::GpuContext;
use crate::kernels::Kernels;

/// What every stage needs besides its buffers.
#[derive(Clone, Copy, Debug)]
pub struct Stage<'a> {
    pub ctx: &'a GpuContext,
    pub kernels: &'a Kernels,
}
