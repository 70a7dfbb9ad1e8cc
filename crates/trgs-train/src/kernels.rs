//! The training stages' kernel table: each stage builds its kernel from its entry here
//! (`TRAINING_KERNELS.adam.build(ctx)`), and the naga test validates every entry's variants.
use trgs_render::Capabilities;
use trgs_render::toolkit::registry::no_defines;

/// The photometric loss's passes over all three colour channels at once
/// (`shaders/shared/loss_channels.wgsl`).
fn rgb(_: &Capabilities) -> Vec<&'static str> {
    vec!["RGB"]
}

trgs_render::kernel_registry! {
    /// Every kernel of the training stages.
    pub const TRAINING_KERNELS: TrainingKernelSpecs => TrainingKernels,
        prelude: crate::layout::prelude, {
        photometric_loss_rows: "training/photometric_loss_rows.wgsl" => no_defines,
        photometric_loss: "training/photometric_loss.wgsl" => no_defines,
        photometric_loss_grad_rows: "training/photometric_loss_grad_rows.wgsl" => no_defines,
        photometric_loss_grad: "training/photometric_loss_grad.wgsl" => no_defines,
        photometric_loss_rows_rgb: "training/photometric_loss_rows.wgsl" => rgb,
        photometric_loss_rgb: "training/photometric_loss.wgsl" => rgb,
        photometric_loss_grad_rows_rgb: "training/photometric_loss_grad_rows.wgsl" => rgb,
        photometric_loss_grad_rgb: "training/photometric_loss_grad.wgsl" => rgb,
        regularisers: "training/regularisers.wgsl" => no_defines,
        exposure: "training/exposure.wgsl" => no_defines,
        exposure_bwd: "training/exposure_bwd.wgsl" => no_defines,
        loss_sums: "training/loss_sums.wgsl" => no_defines,
        adam: "training/adam.wgsl" => no_defines,
        densify_stats: "training/densify_stats.wgsl" => no_defines,
        mcmc_regularise: "training/mcmc_regularise.wgsl" => no_defines,
        mcmc_noise: "training/mcmc_noise.wgsl" => no_defines,
        gather_rows: "training/gather_rows.wgsl" => no_defines,
        densify_plan_candidates: "training/densify_plan_candidates.wgsl" => no_defines,
        densify_plan_rows: "training/densify_plan_rows.wgsl" => no_defines,
        densify_plan_sources: "training/densify_plan_sources.wgsl" => no_defines,
        densify_plan_children: "training/densify_plan_children.wgsl" => no_defines,
        opacity_reset: "training/opacity_reset.wgsl" => no_defines,
        mcmc_relocate_weights: "training/mcmc_relocate_weights.wgsl" => no_defines,
        mcmc_relocate_draw: "training/mcmc_relocate_draw.wgsl" => no_defines,
        mcmc_relocate_shares: "training/mcmc_relocate_shares.wgsl" => no_defines,
        mcmc_relocate_slots: "training/mcmc_relocate_slots.wgsl" => no_defines,
        mcmc_relocate_append: "training/mcmc_relocate_append.wgsl" => no_defines,
        perturb: "training/perturb.wgsl" => no_defines,
        step_guard: "training/step_guard.wgsl" => no_defines,
    }
}
