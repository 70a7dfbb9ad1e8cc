//! The training stages' GPU structs and constants, declared once here in Rust; the WGSL every
//! training kernel sees ([`prelude`]) is the renderer's prelude followed by these, generated.
use crate::densify::mcmc::relocate::{
    MAX_SHARE, RELOCATION_BIN_LO, RELOCATION_BINS, RELOCATION_BINS_PER_UNIT,
};
use trgs_core::metrics::{SSIM_C1, SSIM_C2, SSIM_RADIUS, SSIM_WINDOW, gaussian_window};
use trgs_core::pipeline::{GUARD_KEYS_DROPPED, GUARD_LOSS_NOT_FINITE};
use trgs_core::pipeline::{MAX_REGULARISED_LOG_SCALE, NOISE_GATE_STEEPNESS, NOISE_GATE_THRESHOLD};
use trgs_render::gpu_struct;
use trgs_render::toolkit::layout::{StructInfo, float, struct_info, wgsl_constants};

gpu_struct! {
    /// Parameters of `adam`: one step over `count` floats of one attribute buffer.
    pub struct AdamParams {
        pub count: u32,
        pub lr: f32,
        pub beta1: f32,
        pub beta2: f32,
        pub eps: f32,
        /// 1 - beta1^t and 1 - beta2^t of this step.
        pub bias1: f32,
        pub bias2: f32,
        /// The first `lead` floats of every record of `stride` floats step with `lead_lr` (the SH
        /// DC colour in the SH buffer); stride 0: every float steps with `lr`.
        pub lead: u32,
        pub stride: u32,
        pub lead_lr: f32,
        /// Index in the whole buffer of this range's first float (records are counted from 0).
        pub offset: u32,
        pub pad: u32,
    }
}

/// Pixels per thread of `loss_sums` (the losses' readback is 32 bytes per strip).
pub const LOSS_STRIP: u32 = 64;

/// Pixels per thread of `photometric_loss`'s passes 2-4, consecutive along the pass's blur
/// (shaders/shared/loss_channels.wgsl): a thread reads LOSS_BLUR_RUN + 10 pixels for as many
/// outputs instead of 11 per output. Three, not four: pass 2 keeps five moments per channel and
/// pixel of its run, and on lavapipe its sixty sums a thread at four took twice the time of its
/// forty-five at three, while passes 3 and 4 were no faster at four (`train --profile` times
/// each pass).
pub const LOSS_BLUR_RUN: u32 = 3;

gpu_struct! {
    /// Parameters of the training losses: `photometric_loss` (its four passes), `regularisers`
    /// and `loss_sums`, over one `width` x `height` frame.
    pub struct LossParams {
        pub width: u32,
        pub height: u32,
        /// The D-SSIM weight lambda of `(1 - lambda) L1 + lambda (1 - SSIM)`.
        pub lambda_dssim: f32,
        /// 1 / (width height 3): the photometric loss and L_c are means over samples.
        pub inv_samples: f32,
        /// 1 / (width height): L_d and L_m are means over pixels.
        pub inv_pixels: f32,
        /// The regularisers' weights (`regularisers`).
        pub weight_depth: f32,
        pub weight_conflict: f32,
        /// Zero on views without a glass annotation.
        pub weight_mask: f32,
        /// The first colour channel of this run of `photometric_loss`'s passes (0 for an RGB
        /// run; the one channel of a per-channel run: `losses::ChannelPasses`).
        pub channel: u32,
        /// 1 when `regularisers` ran and wrote its statistics, which `loss_sums` then sums;
        /// 0 leaves their sums zero (the statistics then hold nothing of this frame).
        pub regularisers: u32,
    }
}

gpu_struct! {
    /// Parameters of `mcmc_regularise` and `mcmc_noise` over `count` Gaussians.
    pub struct McmcParams {
        pub count: u32,
        /// The step's random seed (`mcmc_noise`).
        pub seed: u32,
        /// Position learning rate times the noise rate (`mcmc_noise`).
        pub noise_scale: f32,
        /// lambda_o / N and lambda_s / (3 N) (`mcmc_regularise`).
        pub opacity_weight: f32,
        pub scale_weight: f32,
        /// Index in the scene of this range's first Gaussian (numbers the random draws).
        pub first: u32,
        pub pad1: u32,
        pub pad2: u32,
    }
}

gpu_struct! {
    /// Parameters of `densify_stats` over `count` Gaussians (one pass of the frame).
    pub struct DensifyStatsParams {
        pub count: u32,
        /// 1 for the frame's first pass (the camera's): the step's "seen" flags start over.
        pub first_pass: u32,
        /// Half the image's width and height (3DGS measures the gradient in NDC).
        pub half_width: f32,
        pub half_height: f32,
    }
}

gpu_struct! {
    /// Parameters of `gather_rows`: `count` output rows of `width` words each, from the source
    /// rows [`first_source`, `first_source + source_rows`) bound in this dispatch.
    pub struct GatherParams {
        pub count: u32,
        pub width: u32,
        pub first_source: u32,
        pub source_rows: u32,
        /// 1: a source with the GATHER_ZERO bit makes a zero row (Adam moments that restart).
        pub honour_zero: u32,
        /// 1: only the rows whose source has the GATHER_ZERO bit are written, each from the same
        /// row of the source buffer (a plan's given values for the rows it makes anew).
        pub given_rows: u32,
        /// The index of the first output row in the whole set (with `given_rows`).
        pub first_row: u32,
        pub pad0: u32,
    }
}

gpu_struct! {
    /// Parameters of `exposure` and `exposure_bwd` over one `width` x `height` frame: the view's
    /// affine colour map `C' = A C + b`, row `i` being `[A_i0, A_i1, A_i2, b_i]`
    /// ([`trgs_core::pipeline::ExposureMatrix`]).
    pub struct ExposureParams {
        pub row0: [f32; 4],
        pub row1: [f32; 4],
        pub row2: [f32; 4],
        pub width: u32,
        pub height: u32,
        pub pad0: u32,
        pub pad1: u32,
    }
}

gpu_struct! {
    /// Parameters of `step_guard`: `count` vec4s of loss sums to check.
    pub struct StepGuardParams {
        pub count: u32,
        pub pad0: u32,
        pub pad1: u32,
        pub pad2: u32,
    }
}

/// `gather_rows`' source-index bit for an output row that starts from zero (when honoured).
pub const GATHER_ZERO: u32 = 1 << 31;

gpu_struct! {
    /// Parameters of the `densify_plan` kernels over `count` Gaussians: classic densification's
    /// thresholds as the f32 values its twin compares (`classic::decide::Rules`), as logits and
    /// log scales.
    pub struct DensifyPlanParams {
        pub count: u32,
        /// Gaussians that may still be added under `max_gaussians`.
        pub room: u32,
        /// 1: prune Gaussians too large on screen or in the world (after the first reset).
        pub prune_large: u32,
        /// Numbers the split children's random draws.
        pub seed: u32,
        /// Average screen-space gradient norm at which a Gaussian densifies.
        pub grad_threshold: f32,
        /// Opacity logits below this are transparent (pruned, never densified).
        pub transparent_logit: f32,
        /// Largest log scale above which a densifying Gaussian splits rather than clones.
        pub clone_log_scale: f32,
        /// Largest log scale above which a Gaussian is pruned (with `prune_large`).
        pub prune_log_scale: f32,
        /// A split parent's largest log scale above which its children are pruned at once.
        pub child_prune_log_scale: f32,
        /// Screen radius in pixels above which a Gaussian is pruned (with `prune_large`).
        pub max_screen_radius: f32,
        /// ln(1.6): what a child's log scales lose.
        pub child_log_shrink: f32,
        pub pad0: u32,
    }
}

gpu_struct! {
    /// Parameters of `opacity_reset` over `count` Gaussians.
    pub struct OpacityResetParams {
        pub count: u32,
        /// The largest opacity logit left.
        pub cap: f32,
        pub pad0: u32,
        pub pad1: u32,
    }
}

gpu_struct! {
    /// Parameters of the `mcmc_relocate` kernels over a set of `count` Gaussians.
    pub struct McmcRelocateParams {
        pub count: u32,
        /// Gaussians the growth adds (its draws).
        pub growth: u32,
        /// The seed of this round's draws.
        pub seed: u32,
        pub pad0: u32,
        /// Opacity logits at or below this are dead.
        pub dead_logit: f32,
        /// Where Eq. 9's new opacity logits are clamped.
        pub min_logit: f32,
        pub max_logit: f32,
        pub pad1: u32,
    }
}

gpu_struct! {
    /// A plane as `perturb` tests it: its centre with the margin behind it (w), its unit normal
    /// with half its width (w), its width axis with half its height (w), and its height axis.
    pub struct PerturbPlane {
        pub centre: [f32; 4],
        pub normal: [f32; 4],
        pub axis: [f32; 4],
        pub bitangent: [f32; 4],
    }
}

gpu_struct! {
    /// Parameters of `perturb` over `count` Gaussians.
    pub struct PerturbParams {
        pub count: u32,
        pub planes: u32,
        pub cameras: u32,
        pub seed: u32,
        pub amplitude: f32,
        /// Opacities are clamped into [clamp, 1 - clamp].
        pub clamp: f32,
        /// Index in the scene of this range's first Gaussian (numbers the noise).
        pub first: u32,
        pub pad0: u32,
    }
}

/// `densify_plan`'s decision bits per Gaussian: it survives (keeping its Adam moments), it is
/// cloned, it is split into two children (and replaced by them).
pub const DENSIFY_SURVIVOR: u32 = 1;
pub const DENSIFY_CLONE: u32 = 2;
pub const DENSIFY_CHILDREN: u32 = 4;

/// The glass label of a target pixel the photo does not cover (`GpuTarget`): the mask loss skips
/// it, as it has no label.
pub const UNCOVERED_LABEL: u32 = u32::MAX;

/// Every GPU struct of the training stages.
pub fn all_structs() -> Vec<StructInfo> {
    vec![
        struct_info::<AdamParams>(),
        struct_info::<LossParams>(),
        struct_info::<McmcParams>(),
        struct_info::<DensifyStatsParams>(),
        struct_info::<GatherParams>(),
        struct_info::<DensifyPlanParams>(),
        struct_info::<OpacityResetParams>(),
        struct_info::<McmcRelocateParams>(),
        struct_info::<PerturbPlane>(),
        struct_info::<PerturbParams>(),
        struct_info::<StepGuardParams>(),
        struct_info::<ExposureParams>(),
    ]
}

/// The text every training shader starts with: the renderer's prelude, then the training
/// constants and structs.
pub fn prelude() -> String {
    let mut s = trgs_render::toolkit::layout::prelude();
    s.push_str("// Generated by trgs-train (layout.rs).\n");
    let u32s = [
        ("LOSS_STRIP", LOSS_STRIP),
        ("LOSS_BLUR_RUN", LOSS_BLUR_RUN),
        ("GATHER_ZERO", GATHER_ZERO),
        ("DENSIFY_SURVIVOR", DENSIFY_SURVIVOR),
        ("DENSIFY_CLONE", DENSIFY_CLONE),
        ("DENSIFY_CHILDREN", DENSIFY_CHILDREN),
        ("RELOCATION_BINS", RELOCATION_BINS),
        ("MAX_SHARE", MAX_SHARE as u32),
        ("UNCOVERED_LABEL", UNCOVERED_LABEL),
        ("GUARD_KEYS_DROPPED", GUARD_KEYS_DROPPED),
        ("GUARD_LOSS_NOT_FINITE", GUARD_LOSS_NOT_FINITE),
    ];
    let f32s = [
        ("NOISE_GATE_STEEPNESS".to_string(), NOISE_GATE_STEEPNESS),
        ("NOISE_GATE_THRESHOLD".to_string(), NOISE_GATE_THRESHOLD),
        ("MAX_REGULARISED_LOG_SCALE".to_string(), MAX_REGULARISED_LOG_SCALE),
        ("RELOCATION_BIN_LO".to_string(), f64::from(RELOCATION_BIN_LO)),
        ("RELOCATION_BINS_PER_UNIT".to_string(), f64::from(RELOCATION_BINS_PER_UNIT)),
        ("SSIM_C1".to_string(), SSIM_C1),
        ("SSIM_C2".to_string(), SSIM_C2),
    ];
    s.push_str(&wgsl_constants(&u32s, &f32s));
    // The SSIM window of trgs_core::metrics (photometric_loss blurs with it).
    let window: Vec<String> = gaussian_window().iter().map(|&v| float(v)).collect();
    s.push_str(&format!(
        "const SSIM_RADIUS: u32 = {SSIM_RADIUS}u;\nconst SSIM_WEIGHTS = array<f32, {SSIM_WINDOW}>({});\n",
        window.join(", ")
    ));
    for (_, decl, _, _) in all_structs() {
        s.push_str(&decl);
    }
    s
}
