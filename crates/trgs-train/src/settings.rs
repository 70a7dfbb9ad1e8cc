//! Every setting of a training run, with the paper's and 3DGS's values as defaults. Lengths are
//! given for the paper's 30k iterations and scale with `iterations`.
use crate::exposure::ExposureRates;
use trgs_core::pipeline::{AdamRate, DSSIM_LAMBDA, ReflectionModel};
use trgs_core::scene::{Attribute, PerAttribute};

/// The paper's iteration budget, which the default lengths below refer to.
pub const PAPER_ITERATIONS: u32 = 30_000;

/// Learning rates (3DGS's defaults for the Gaussians; the position rate is multiplied by the
/// scene extent and decays exponentially from `position` to `position_final` over the run).
#[derive(Clone, Debug, PartialEq)]
pub struct LearningRates {
    pub position: f64,
    pub position_final: f64,
    /// SH DC colour; the higher bands use `sh_rest`.
    pub sh_dc: f64,
    pub sh_rest: f64,
    pub opacity: f64,
    pub scale: f64,
    pub rotation: f64,
    /// The glass-mask logit of glass Gaussians (not given by the paper; as the opacity logit's).
    pub mask: f64,
    /// The log reflection intensity (not given by the paper; as the DC colour's).
    pub reflection: f64,
    /// Plane centre (times the extent), unnormalised normal and R0 logit; stage 3 multiplies the
    /// centre and normal rates by `plane_stage3_factor` (paper: 0.1). The paper gives no plane
    /// rates. The normal's is small because the fit from the masks is already within a fraction of
    /// a degree, and at four times this rate the normal drifts away from it by degrees.
    pub plane_centre: f64,
    pub plane_normal: f64,
    pub plane_r0: f64,
    pub plane_stage3_factor: f64,
}

impl Default for LearningRates {
    fn default() -> Self {
        Self {
            position: 1.6e-4,
            position_final: 1.6e-6,
            sh_dc: 2.5e-3,
            sh_rest: 2.5e-3 / 20.0,
            opacity: 2.5e-2,
            scale: 5e-3,
            rotation: 1e-3,
            mask: 2.5e-2,
            reflection: 2.5e-3,
            plane_centre: 1e-3,
            plane_normal: 2.5e-4,
            plane_r0: 1e-2,
            plane_stage3_factor: 0.1,
        }
    }
}

impl LearningRates {
    /// The position rate at `step` of `iterations` (log-linear from start to final), times
    /// `extent`.
    pub fn position_at(&self, step: u32, iterations: u32, extent: f64) -> f64 {
        let t = (f64::from(step) / f64::from(iterations.max(1))).clamp(0.0, 1.0);
        let ln = (1.0 - t) * self.position.ln() + t * self.position_final.ln();
        ln.exp() * extent
    }

    /// The rate of every attribute at `step`.
    pub fn attribute_rates(
        &self,
        step: u32,
        iterations: u32,
        extent: f64,
        sh_coeffs: u32,
    ) -> PerAttribute<AdamRate> {
        PerAttribute::from_fn(|a| match a {
            Attribute::Means => AdamRate::uniform(self.position_at(step, iterations, extent)),
            Attribute::Rotations => AdamRate::uniform(self.rotation),
            Attribute::LogScales => AdamRate::uniform(self.scale),
            Attribute::OpacityLogits => AdamRate::uniform(self.opacity),
            // The DC colour (the first 3 floats of each Gaussian's record) has its own rate.
            Attribute::Sh => {
                AdamRate { lr: self.sh_rest, lead_lr: self.sh_dc, lead: 3, stride: 3 * sh_coeffs }
            }
            Attribute::MaskLogits => AdamRate::uniform(self.mask),
            Attribute::LogReflections => AdamRate::uniform(self.reflection),
        })
    }
}

/// A training run's settings.
#[derive(Clone, Debug, PartialEq)]
pub struct TrainSettings {
    pub iterations: u32,
    /// Largest SH degree; the active degree grows by one every `sh_interval` steps.
    pub sh_degree: u32,
    pub sh_interval: u32,
    /// Weight of D-SSIM in the image loss.
    pub lambda_dssim: f64,
    pub background: [f32; 3],
    pub rates: LearningRates,
    /// Shuffles the order of the training views.
    pub seed: u64,
    /// Stage 1 (C = C_t, plain 3DGS) and stage 2 (planes learn, the reflection's gradient does
    /// not reach the Gaussians) lengths; stage 3 is the rest (paper: 3000, 3000, 24000).
    pub stage1: u32,
    pub stage2: u32,
    /// Weights of the depth-variance, gradient-conflict and mask losses (paper: 0.005, 0.2, 0.5).
    pub lambda_depth: f64,
    pub lambda_conflict: f64,
    pub lambda_mask: f64,
    /// Opacity perturbation in stage 3 (None: off).
    pub perturb: Option<PerturbSchedule>,
    /// The reflection model (ablations switch Schlick or the intensity map off).
    pub reflection: ReflectionModel,
    /// Per-view exposure compensation and its learning rates (None: off).
    pub exposure: Option<ExposureRates>,
}

/// The paper's opacity perturbation noise: uniform in [-0.4, 0.4] on the opacity (not its
/// logit).
pub const PERTURB_AMPLITUDE: f64 = 0.4;

/// When the opacity perturbation runs: every `every` steps of stage 3 from `from` and before
/// `until`, skipping the steps of an opacity reset (the paper interleaves the two).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PerturbSchedule {
    pub every: u32,
    /// The first step it may run at: `--planes auto` holds it back while candidate planes are on
    /// trial, so that a dropped candidate has not shaken the model it leaves behind.
    pub from: u32,
    pub until: u32,
    /// Half-width of the uniform noise on the opacity (paper: 0.4).
    pub amplitude: f64,
}

impl PerturbSchedule {
    /// The paper's every 1000 steps, scaled, but at least 100 steps apart so that a short run
    /// has time to recover from each; none in the last tenth of the run, which is for settling.
    pub fn scaled(iterations: u32) -> Self {
        Self {
            every: scale_len(1000, iterations).max(100),
            from: 0,
            until: iterations - iterations / 10,
            amplitude: PERTURB_AMPLITUDE,
        }
    }
}

/// The three stages of the optimisation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    Initial,
    PlaneAdjustment,
    Joint,
}

impl TrainSettings {
    /// The paper's settings scaled to `iterations` steps.
    pub fn scaled(iterations: u32) -> Self {
        Self {
            iterations,
            sh_degree: 3,
            sh_interval: scale_len(1000, iterations),
            lambda_dssim: DSSIM_LAMBDA,
            background: [0.0; 3],
            rates: LearningRates::default(),
            seed: 0,
            stage1: scale_len(3000, iterations),
            stage2: scale_len(3000, iterations),
            lambda_depth: 0.005,
            lambda_conflict: 0.2,
            lambda_mask: 0.5,
            perturb: Some(PerturbSchedule::scaled(iterations)),
            reflection: ReflectionModel::default(),
            exposure: None,
        }
    }

    /// The stage of step `step` (0-based).
    pub fn stage(&self, step: u32) -> Stage {
        if step < self.stage1 {
            Stage::Initial
        } else if step < self.stage1 + self.stage2 {
            Stage::PlaneAdjustment
        } else {
            Stage::Joint
        }
    }

    /// Whether the opacity perturbation's schedule runs after step `t` (the trainer also skips
    /// it without planes and at an opacity reset).
    pub fn perturbs_at(&self, t: u32) -> bool {
        self.perturb.is_some_and(|p| {
            self.stage(t) == Stage::Joint && t >= p.from && t < p.until && t.is_multiple_of(p.every)
        })
    }

    /// The SH degree of the model after `steps` steps, which the step that brings the count to
    /// `steps` already trains with: 3DGS raises it at the start of iterations 1000, 2000 and 3000
    /// (counted from 1), so the step numbered 1000 renders with degree 1.
    pub fn active_sh_degree(&self, steps: u32) -> u32 {
        (steps / self.sh_interval.max(1)).min(self.sh_degree)
    }
}

/// A length given for the paper's 30k iterations, scaled to `iterations` (at least 1).
pub fn scale_len(paper: u32, iterations: u32) -> u32 {
    ((u64::from(paper) * u64::from(iterations)) / u64::from(PAPER_ITERATIONS)).max(1) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn position_rate_decays_log_linearly() {
        let r = LearningRates::default();
        assert!((r.position_at(0, 100, 2.0) - 3.2e-4).abs() < 1e-12);
        assert!((r.position_at(100, 100, 2.0) - 3.2e-6).abs() < 1e-14);
        assert!((r.position_at(50, 100, 1.0) - 1.6e-5).abs() < 1e-12);
    }

    #[test]
    fn lengths_scale_with_the_budget() {
        let s = TrainSettings::scaled(3000);
        assert_eq!(s.sh_interval, 100);
        assert_eq!(s.active_sh_degree(0), 0);
        assert_eq!(s.active_sh_degree(250), 2);
        assert_eq!(s.active_sh_degree(2999), 3);
        // 3DGS at 30k steps: degree 1 from the step numbered 1000, 3 from 3000.
        let s = TrainSettings::scaled(30_000);
        assert_eq!(s.active_sh_degree(999), 0);
        assert_eq!(s.active_sh_degree(1000), 1);
        assert_eq!(s.active_sh_degree(3000), 3);
    }

    #[test]
    fn the_perturbation_runs_in_stage3_from_its_first_step() {
        // 2000 steps: stage 3 from 400, every 100 steps, none in the last tenth.
        let mut s = TrainSettings::scaled(2000);
        let at = |s: &TrainSettings| (0..2000).filter(|&t| s.perturbs_at(t)).collect::<Vec<_>>();
        assert_eq!(at(&s), (4..18).map(|k| 100 * k).collect::<Vec<_>>());
        s.perturb.as_mut().expect("on").from = 601;
        assert_eq!(at(&s), (7..18).map(|k| 100 * k).collect::<Vec<_>>());
        s.perturb = None;
        assert!(at(&s).is_empty());
    }
}
