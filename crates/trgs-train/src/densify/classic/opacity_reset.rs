//! Stage `opacity_reset` on the GPU (shaders/training/opacity_reset.wgsl; twin
//! [`crate::densify::classic::opacity_reset_logits`]): every opacity logit capped in place, without
//! reading the opacities back.
use crate::kernels::TRAINING_KERNELS;
use crate::layout::OpacityResetParams;
use trgs_core::scene::Attribute;
use trgs_render::GpuContext;
use trgs_render::GpuScene;
use trgs_render::toolkit::gpu::{self, Kernel, Recorder, grid_1d, range};

#[derive(Debug)]
pub struct GpuOpacityReset {
    kernel: Kernel,
}

impl GpuOpacityReset {
    pub fn new(ctx: &GpuContext) -> Self {
        Self { kernel: TRAINING_KERNELS.opacity_reset.build(ctx) }
    }

    /// Record the cap of every opacity logit of `scene` at `cap`.
    pub fn record(&self, ctx: &GpuContext, rec: &mut Recorder, scene: &GpuScene, cap: f32) {
        let opacity = scene.parameter(Attribute::OpacityLogits);
        for (first, count) in scene.chunks() {
            let params = OpacityResetParams { count, cap, ..Default::default() };
            let block = gpu::params(ctx, "trgs.opacity_reset.params", &params);
            let (f, c) = (u64::from(first), u64::from(count));
            let bind =
                self.kernel.bind(ctx, &[block.as_entire_binding(), range(opacity, f * 4, c * 4)]);
            rec.dispatch("opacity_reset", &self.kernel, &bind, grid_1d(count.div_ceil(256)));
        }
    }
}

/// The logit of 3DGS's opacity reset: every opacity becomes at most 0.01.
pub fn opacity_reset_cap() -> f32 {
    (0.01f64 / 0.99).ln() as f32
}

/// 3DGS's opacity reset of the logits (the twin of `opacity_reset`, which training runs).
pub fn opacity_reset_logits(logits: &mut [f32]) {
    let cap = opacity_reset_cap();
    for o in logits {
        // A NaN becomes the cap too, as on the GPU.
        if !(*o <= cap) {
            *o = cap;
        }
    }
}
