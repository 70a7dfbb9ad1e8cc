//! Stages `mcmc_regularise` and `mcmc_noise` on the GPU (shaders/training/mcmc_regularise.wgsl,
//! shaders/training/mcmc_noise.wgsl; twins `trgs_core::reference::mcmc_regularise` and
//! `mcmc_noise`): the regularisers' gradients before Adam and the exploration noise after it,
//! every step.
use super::settings::McmcSettings;
use crate::kernels::TRAINING_KERNELS;
use crate::layout::McmcParams;
use trgs_core::pipeline::AdamRate;
use trgs_core::scene::Attribute;
use trgs_render::toolkit::gpu::{self, Kernel, Recorder, grid_1d, range};
use trgs_render::{GpuContext, GpuScene, SceneGradBuffers};

/// The two per-step GPU stages.
#[derive(Debug)]
pub struct McmcKernels {
    regularise: Kernel,
    noise: Kernel,
}

impl McmcKernels {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            regularise: TRAINING_KERNELS.mcmc_regularise.build(ctx),
            noise: TRAINING_KERNELS.mcmc_noise.build(ctx),
        }
    }

    /// Record `mcmc_regularise`: add the regularisers' gradients to `grads`.
    pub fn record_regularise(
        &self,
        ctx: &GpuContext,
        rec: &mut Recorder,
        scene: &GpuScene,
        grads: &SceneGradBuffers,
        settings: &McmcSettings,
    ) {
        let n = f64::from(scene.len().max(1));
        let base = McmcParams {
            opacity_weight: (settings.opacity_weight / n) as f32,
            scale_weight: (settings.scale_weight / (3.0 * n)) as f32,
            ..Default::default()
        };
        let p = scene.parameters();
        let (log_scales, opacities) = (p[Attribute::LogScales], p[Attribute::OpacityLogits]);
        for (first, count) in scene.chunks() {
            let block =
                gpu::params(ctx, "trgs.mcmc_regularise.params", &McmcParams { count, ..base });
            let (f, c) = (u64::from(first), u64::from(count));
            let bind = self.regularise.bind(
                ctx,
                &[
                    block.as_entire_binding(),
                    range(log_scales, f * 12, c * 12),
                    range(opacities, f * 4, c * 4),
                    range(scene.populations(), f * 4, c * 4),
                    range(grads.parameter(Attribute::LogScales), f * 12, c * 12),
                    range(grads.parameter(Attribute::OpacityLogits), f * 4, c * 4),
                ],
            );
            rec.dispatch("mcmc_regularise", &self.regularise, &bind, grid_1d(count.div_ceil(256)));
        }
    }

    /// Record `mcmc_noise` with the position learning rate `position_lr` of this step.
    pub fn record_noise(
        &self,
        ctx: &GpuContext,
        rec: &mut Recorder,
        scene: &GpuScene,
        settings: &McmcSettings,
        position_lr: &AdamRate,
        seed: u32,
        guard: &wgpu::Buffer,
    ) {
        let base = McmcParams {
            seed,
            noise_scale: (settings.noise_rate * position_lr.lr) as f32,
            ..Default::default()
        };
        let p = scene.parameters();
        for (first, count) in scene.chunks() {
            let block =
                gpu::params(ctx, "trgs.mcmc_noise.params", &McmcParams { count, first, ..base });
            let (f, c) = (u64::from(first), u64::from(count));
            let bind = self.noise.bind(
                ctx,
                &[
                    block.as_entire_binding(),
                    range(p[Attribute::Means], f * 12, c * 12),
                    range(p[Attribute::Rotations], f * 16, c * 16),
                    range(p[Attribute::LogScales], f * 12, c * 12),
                    range(p[Attribute::OpacityLogits], f * 4, c * 4),
                    range(scene.populations(), f * 4, c * 4),
                    guard.as_entire_binding(),
                ],
            );
            rec.dispatch("mcmc_noise", &self.noise, &bind, grid_1d(count.div_ceil(256)));
        }
    }
}
