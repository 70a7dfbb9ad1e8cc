//! Stage `step_guard` on the GPU (shaders/training/step_guard.wgsl; twin
//! `trgs_core::reference::step_guard`): one word that says whether a training step may change
//! the model, set on the GPU after the loss, so that the step's updates (`adam`, `mcmc_noise`,
//! `densify_stats`) are recorded before its loss and key totals come back. A step whose frame
//! dropped keys, or whose loss is not finite, then changes nothing; the trainer reads the word
//! with the loss and says which.
use crate::layout::StepGuardParams;
use trgs_render::GpuContext;
use trgs_render::toolkit::gpu::{self, Kernel, Recorder, grid_1d};

/// The guard word of a trainer's steps and its kernel.
#[derive(Debug)]
pub struct StepGuard {
    kernel: Kernel,
    word: wgpu::Buffer,
}

impl StepGuard {
    pub fn new(ctx: &GpuContext) -> Self {
        Self { kernel: crate::kernels::TRAINING_KERNELS.step_guard.build(ctx), word: open(ctx) }
    }

    /// The word the step's updates read (its first u32): zero lets them change the model.
    pub fn word(&self) -> &wgpu::Buffer {
        &self.word
    }

    /// Record the guard of a step: cleared, then set from `sums` (the loss strips' sums,
    /// `vec4s` of them) and `kept` (the frame's `emit_keys` words: kept keys, then whether keys
    /// were dropped).
    pub fn record(
        &self,
        ctx: &GpuContext,
        rec: &mut Recorder,
        sums: &wgpu::Buffer,
        vec4s: u32,
        kept: &wgpu::Buffer,
    ) {
        rec.encoder.clear_buffer(&self.word, 0, None);
        let params = StepGuardParams { count: vec4s, ..Default::default() };
        let block = gpu::params(ctx, "trgs.step_guard.params", &params);
        let bind = self.kernel.bind(
            ctx,
            &[
                block.as_entire_binding(),
                sums.as_entire_binding(),
                kept.as_entire_binding(),
                self.word.as_entire_binding(),
            ],
        );
        rec.dispatch("step_guard", &self.kernel, &bind, grid_1d(vec4s.max(1).div_ceil(256)));
    }
}

/// A guard word that stays zero: for recording a step's updates outside a training step (tests
/// and tools that run `adam`, `mcmc_noise` or `densify_stats` alone).
pub fn open(ctx: &GpuContext) -> wgpu::Buffer {
    gpu::storage_init(ctx, "trgs.step_guard.word", &[0u32; 4])
}
