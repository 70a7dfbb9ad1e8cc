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

/// How many values a scan or a sort covers.
#[derive(Clone, Copy, Debug)]
pub enum ItemCount<'a> {
    Known(u32),
    /// The first u32 of `counter`, known on the GPU only; the dispatches cover `capacity`, and
    /// their blocks past the count return at once (spread over the workgroups:
    /// [`ItemCount::spread`]).
    OnGpu {
        counter: &'a wgpu::Buffer,
        capacity: u32,
    },
}

impl ItemCount<'_> {
    /// The most values the count can be (what the dispatches cover).
    pub fn capacity(&self) -> u32 {
        match *self {
            ItemCount::Known(n) => n,
            ItemCount::OnGpu { capacity, .. } => capacity,
        }
    }

    /// The workgroup permutation's step for a dispatch of `groups` over the capacity
    /// ([`crate::gpu::spread_step`]): none for a known count, whose blocks are all full.
    pub fn spread(&self, groups: [u32; 3]) -> u32 {
        match *self {
            ItemCount::Known(_) => 0,
            ItemCount::OnGpu { .. } => crate::gpu::spread_step(groups),
        }
    }

    /// Copies a GPU count into the first word of `params` (where every parameter block that
    /// takes one holds its count: checked below for those that do).
    pub fn write_into(&self, rec: &mut crate::gpu::Recorder, params: &wgpu::Buffer) {
        if let ItemCount::OnGpu { counter, .. } = *self {
            rec.encoder.copy_buffer_to_buffer(counter, 0, params, 0, 4);
        }
    }
}

// `ItemCount::write_into` writes a parameter block's first word.
const _: () = assert!(std::mem::offset_of!(crate::layout::ScanParams, count) == 0);
const _: () = assert!(std::mem::offset_of!(crate::layout::SortParams, count) == 0);
const _: () = assert!(std::mem::offset_of!(crate::layout::EmitParams, entries) == 0);
