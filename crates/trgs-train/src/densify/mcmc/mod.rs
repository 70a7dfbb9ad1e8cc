//! MCMC densification (3DGS-MCMC, Kheradmand et al. 2024), the alternative to classic
//! densification selected by `--densify mcmc`:
//! - every step, the regularisers' gradients (`mcmc_regularise`) before Adam and the exploration
//!   noise on the means (`mcmc_noise`) after it, both on the GPU;
//! - every `every` steps of [from, until), decided on the GPU (`mcmc_relocate`, twin
//!   [`plan_relocation`]) and carried out there (`gather_rows`): dead Gaussians (opacity at most
//!   `min_opacity`) are moved onto live ones drawn in proportion to their opacity, then 5% more
//!   Gaussians are added the same way, up to `cap`. A Gaussian that receives
//!   N - 1 copies and its copies all take the opacity and scale of the paper's Eq. 9, so that the
//!   N of them render about as the one did. Moved and sampled Gaussians restart their Adam moments.
//!
//! The relocation's plan on the CPU (the twin of `mcmc_relocate`) and the tables both sides use
//! are in [`relocate`].
//!
//! There is no pruning and no opacity reset. Glass Gaussians are never moved, sampled or noised:
//! they belong to their plane.
pub mod relocate;

pub(crate) use relocate::relocation_seeds;
pub use relocate::{
    MAX_SHARE, RELOCATION_BIN_LO, RELOCATION_BINS, RELOCATION_BINS_PER_UNIT, RelocationLimits,
    draw, growth_rows, opacity_bin, plan_relocation, relocate_and_grow, relocation,
    relocation_table, weight_table,
};

use super::{DensifyEvent, DensifyStrategy, StepView};
use crate::gaussian_state::GaussianState;
use crate::kernels::TRAINING_KERNELS;
use crate::layout::McmcParams;
use crate::mcmc_relocate::{GpuMcmcRelocate, PendingMcmcRelocate};
use crate::settings::scale_len;
use anyhow::{Context, Result};
use trgs_core::reference::AdamRate;
use trgs_core::rng::Rng;
use trgs_core::scene::Attribute;
use trgs_render::toolkit::gpu::{self, Kernel, Recorder, grid_1d, range};
use trgs_render::{GpuContext, GpuScene, SceneGradBuffers};

/// The shortest relocation interval in steps (each relocation rebuilds every buffer: several
/// steps' time, `bench --densify`).
pub const MIN_RELOCATION_INTERVAL: u32 = 5;

/// 3DGS-MCMC's opacity learning rate (its `arguments/__init__.py`), twice 3DGS's 0.025: its
/// regulariser pulls opacities down all through the run and relocation needs dead Gaussians.
pub const OPACITY_LEARNING_RATE: f64 = 0.05;

/// The schedule and constants (the paper's values for 30k steps; lengths scale with the run).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct McmcSettings {
    pub from: u32,
    pub until: u32,
    pub every: u32,
    /// Never more Gaussians than this.
    pub cap: usize,
    /// Gaussians at or below this opacity are dead and get relocated.
    pub min_opacity: f64,
    /// Growth per relocation step (1.05: 5% more Gaussians).
    pub growth: f64,
    /// The noise's rate relative to the position learning rate (the paper's 5e5).
    pub noise_rate: f64,
    /// Weights of mean(opacity) and mean(scale) in the loss (the paper's 0.01 each).
    pub opacity_weight: f64,
    pub scale_weight: f64,
}

impl McmcSettings {
    /// The paper's settings with the count capped at `cap`. The relocation interval scales with
    /// the run like every other length (at least 5 steps, which bounds the cost of the
    /// relocations, each a rebuild of the set, in very short runs): growing 5% per relocation,
    /// a run then reaches its cap at the same fraction of its length as the paper's run does. A
    /// fixed floor of 20 steps made a 2000-step run reach its cap at 64% of the run, where
    /// classic densification has its count at 50%, and MCMC trained with about half as many
    /// Gaussians until then.
    pub fn scaled(iterations: u32, cap: usize) -> Self {
        Self {
            from: scale_len(500, iterations),
            until: scale_len(25_000, iterations),
            every: scale_len(100, iterations).max(MIN_RELOCATION_INTERVAL),
            cap,
            min_opacity: 0.005,
            growth: 1.05,
            noise_rate: 5e5,
            opacity_weight: 0.01,
            scale_weight: 0.01,
        }
    }

    /// Whether step `t` (1-based, after its optimiser step) relocates and grows.
    pub fn relocates_at(&self, t: u32) -> bool {
        t > self.from && t < self.until && t.is_multiple_of(self.every)
    }
}

/// What one relocation step did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct McmcReport {
    pub relocated: usize,
    pub added: usize,
}

impl McmcReport {
    /// How many times the keys of a frame may grow after this step on a set of `n`: every
    /// relocated or added Gaussian copies a live one, drawn by opacity, so as many more as
    /// those per Gaussian of the set (most of which MCMC keeps live).
    pub fn key_growth(&self, n: usize) -> f64 {
        1.0 + (self.relocated + self.added) as f64 / n.max(1) as f64
    }
}

/// MCMC densification as a [`DensifyStrategy`].
#[derive(Debug)]
pub struct McmcDensification {
    ctx: GpuContext,
    settings: McmcSettings,
    kernels: McmcKernels,
    relocation: GpuMcmcRelocate,
    /// Decide on the GPU where the set fits (see [`McmcDensification::decide_on_cpu`]).
    on_gpu: bool,
    /// A relocation decided on the GPU whose counters are on their way back
    /// ([`DensifyStrategy::settle`]).
    pending: Option<PendingMcmcRelocate>,
}

impl McmcDensification {
    pub fn new(ctx: &GpuContext, settings: McmcSettings) -> Self {
        Self {
            ctx: ctx.clone(),
            settings,
            kernels: McmcKernels::new(ctx),
            relocation: GpuMcmcRelocate::new(ctx),
            on_gpu: true,
            pending: None,
        }
    }

    pub fn settings(&self) -> &McmcSettings {
        &self.settings
    }

    /// Decide on the CPU from attributes read back, as sets too large for `mcmc_relocate`'s
    /// bindings are (for tests and `bench --densify`).
    pub fn decide_on_cpu(&mut self) {
        self.on_gpu = false;
    }

    /// A relocation and growth step now (the schedule calls it every `every` steps). Decided on
    /// the GPU (`mcmc_relocate`) when the set fits its bindings, otherwise on the CPU from the
    /// few attributes read back; both draw two seeds from `rng` and make the same plan.
    pub fn relocate_now(
        &mut self,
        gaussians: &mut GaussianState,
        rng: &mut Rng,
    ) -> Result<McmcReport> {
        if let Some(report) = self.relocate_or_defer(gaussians, rng)? {
            return Ok(report);
        }
        self.settle_relocate(gaussians)?.context("a relocation was planned")
    }

    /// [`McmcDensification::relocate_now`], but a relocation decided on the GPU is left pending
    /// (None), for [`McmcDensification::settle_relocate`] to apply once its counters are back.
    fn relocate_or_defer(
        &mut self,
        gaussians: &mut GaussianState,
        rng: &mut Rng,
    ) -> Result<Option<McmcReport>> {
        anyhow::ensure!(self.pending.is_none(), "a relocation is already pending");
        let (n, growth) = (gaussians.len(), growth_rows(&self.settings, gaussians.len()));
        if !(self.on_gpu && GpuMcmcRelocate::fits(&self.ctx, n, growth)) {
            let (plan, report) = plan_relocation(&gaussians.geometry()?, &self.settings, rng);
            gaussians.apply_plan(&plan)?;
            return Ok(Some(report));
        }
        let limits = RelocationLimits::new(self.settings.min_opacity);
        let seeds = relocation_seeds(rng);
        let scene = gaussians.scene();
        self.pending =
            Some(self.relocation.record(&self.ctx, scene, &limits, growth as u32, seeds)?);
        Ok(None)
    }

    /// Apply the pending relocation, if any.
    fn settle_relocate(&mut self, gaussians: &mut GaussianState) -> Result<Option<McmcReport>> {
        let Some(pending) = self.pending.take() else { return Ok(None) };
        let plan = pending.settle(&self.ctx)?;
        anyhow::ensure!(plan.count() == gaussians.len(), "a relocation of another set");
        gaussians.apply_mcmc_relocate(&plan)?;
        Ok(Some(plan.report))
    }
}

impl DensifyStrategy for McmcDensification {
    fn name(&self) -> &'static str {
        "mcmc"
    }

    fn cap(&self) -> Option<usize> {
        Some(self.settings.cap)
    }

    fn record_before_adam(&self, step: &StepView<'_>, rec: &mut Recorder) {
        let grads = &step.grads.gaussians;
        self.kernels.record_regularise(step.ctx, rec, step.scene, grads, &self.settings);
    }

    fn record_after_adam(&self, step: &StepView<'_>, rec: &mut Recorder) {
        // A seed per step (the step survives a resume, so the noise does too).
        let seed = (step.seed as u32).wrapping_mul(0x9e37_79b9) ^ step.step;
        let position = &step.rates[Attribute::Means];
        let (ctx, scene, guard) = (step.ctx, step.scene, step.guard);
        self.kernels.record_noise(ctx, rec, scene, &self.settings, position, seed, guard);
    }

    fn maintain(
        &mut self,
        step: u32,
        gaussians: &mut GaussianState,
        rng: &mut Rng,
        _extent: f64,
    ) -> Result<Vec<DensifyEvent>> {
        if !self.settings.relocates_at(step) {
            return Ok(Vec::new());
        }
        // Decided on the GPU, the relocation is applied by `settle` (its counters a step late).
        let done = self.relocate_or_defer(gaussians, rng)?;
        Ok(done.map(DensifyEvent::Relocated).into_iter().collect())
    }

    fn settle(&mut self, gaussians: &mut GaussianState) -> Result<Vec<DensifyEvent>> {
        let done = self.settle_relocate(gaussians)?;
        Ok(done.map(DensifyEvent::Relocated).into_iter().collect())
    }

    fn pending(&self) -> bool {
        self.pending.is_some()
    }

    fn restart(&mut self, _n: usize) {
        self.pending = None;
    }
}

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

#[cfg(test)]
mod tests {
    use super::relocate::logit;
    use super::*;
    use crate::densify::{TrainState, sigmoid};
    use trgs_core::scene::{Gaussians, PerAttribute, Population};

    /// N copies at the relocated opacity composite to the old opacity where they overlap
    /// (1 - (1 - o')^N = o), and one share leaves a Gaussian unchanged.
    #[test]
    fn relocation_keeps_opacity_and_identity() {
        let (o1, f1) = relocation(0.6, 1, 0.005);
        assert!((o1 - 0.6).abs() < 1e-12 && (f1 - 1.0).abs() < 1e-12, "{o1} {f1}");
        for share in [2, 3, 5, 20, 51, 80] {
            let (o, f) = relocation(0.8, share, 0.005);
            let n = share.min(MAX_SHARE) as i32;
            assert!((1.0 - (1.0 - o).powi(n) - 0.8).abs() < 1e-9, "share {share}: {o}");
            assert!(f.is_finite() && f > 0.0, "share {share}: scale factor {f}");
        }
        // A faint source: the copies' opacity is clamped to the floor, but their scale comes
        // from Eq. 9's unclamped opacity (about o / n each, so about the source's scale).
        let (o, f) = relocation(0.01, 3, 0.005);
        assert_eq!(o, 0.005);
        assert!((f - 1.0).abs() < 0.01, "scale factor {f}");
        // Two copies of an opaque Gaussian must each be wider than half its footprint.
        let (_, f) = relocation(0.9, 2, 0.005);
        assert!(f > 0.5 && f < 2.0, "{f}");
    }

    fn state(opacities: &[f64]) -> TrainState {
        let mut g = Gaussians::<f32>::zeros(opacities.len(), 1);
        g.rotations = vec![[1.0, 0.0, 0.0, 0.0]; opacities.len()];
        g.opacity_logits = opacities.iter().map(|&o| logit(o)).collect();
        for (i, m) in g.means.iter_mut().enumerate() {
            *m = [i as f32, 0.0, 0.0];
        }
        let w = trgs_core::scene::attribute_widths(g.sh_coeffs());
        let ones = |a: Attribute| vec![1.0f32; opacities.len() * w[a]];
        TrainState { m: PerAttribute::from_fn(ones), v: PerAttribute::from_fn(ones), gaussians: g }
    }

    /// Growing 5% per relocation from 4000 to a 20 times larger cap (the synthetic scene's
    /// sparse points to a classic run's final count), a run reaches the cap at about the same
    /// fraction of its length as the paper's 30k-step run, not late in a short run.
    #[test]
    fn the_cap_is_reached_at_the_papers_fraction_of_the_run() {
        let fraction = |iterations: u32| {
            let settings = McmcSettings::scaled(iterations, 80_000);
            let mut n = 4000usize;
            let step = (1..=iterations)
                .find(|&t| {
                    if settings.relocates_at(t) {
                        n = ((settings.growth * n as f64) as usize).min(settings.cap);
                    }
                    n == settings.cap
                })
                .expect("the cap is reached");
            f64::from(step) / f64::from(iterations)
        };
        let paper = fraction(30_000);
        for iterations in [2000, 5000] {
            let f = fraction(iterations);
            println!("{iterations} steps: cap at {f:.3} of the run (paper: {paper:.3})");
            assert!(f < paper + 0.05, "{iterations} steps: cap at {f} of the run");
        }
        assert!(McmcSettings::scaled(100, 10).every >= MIN_RELOCATION_INTERVAL);
    }

    #[test]
    fn dead_gaussians_move_onto_live_ones_and_the_count_grows() {
        let mut s = state(&[0.9, 0.001, 0.5, 0.002, 0.7, 0.3, 0.8, 0.6, 0.4, 0.95, 0.85, 0.65]);
        s.gaussians.populations[11] = Population::Glass;
        let settings = McmcSettings { cap: 100, ..McmcSettings::scaled(30_000, 100) };
        let (out, report) = relocate_and_grow(&s, &settings, &mut Rng::new(3));
        assert_eq!(report.relocated, 2);
        assert_eq!(report.added, 12 * 105 / 100 - 12);
        let g = &out.gaussians;
        assert_eq!(g.len(), 12 + report.added);
        for d in [1, 3] {
            let o = sigmoid(f64::from(g.opacity_logits[d]));
            assert!(o > settings.min_opacity, "slot {d} is still dead: {o}");
            let copy_of = (0..12).find(|&j| j != d && g.means[j] == g.means[d]);
            assert!(copy_of.is_some(), "slot {d} holds a copy of a live Gaussian");
            assert_eq!(out.m[Attribute::Means][3 * d], 0.0, "moved Gaussians restart Adam");
        }
        // The glass Gaussian is never a source, a slot or touched.
        assert_eq!(g.opacity_logits[11], s.gaussians.opacity_logits[11]);
        assert!(g.means[12..].iter().all(|m| *m != s.gaussians.means[11]));
        assert_eq!(out.m[Attribute::Means][3 * 11], 1.0);
    }

    #[test]
    fn growth_stops_at_the_cap() {
        let s = state(&[0.5; 40]);
        let settings = McmcSettings { cap: 41, ..McmcSettings::scaled(30_000, 41) };
        let (out, report) = relocate_and_grow(&s, &settings, &mut Rng::new(1));
        assert_eq!((report.relocated, report.added, out.gaussians.len()), (0, 1, 41));
        let (out, _) = relocate_and_grow(&out, &settings, &mut Rng::new(1));
        assert_eq!(out.gaussians.len(), 41);
    }
}
