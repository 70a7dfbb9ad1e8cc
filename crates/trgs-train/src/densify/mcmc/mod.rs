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
pub mod mcmc_relocate;
pub mod relocate;
pub mod settings;
pub mod step_kernels;

pub use mcmc_relocate::{GpuMcmcRelocate, McmcRelocateOutput};
pub use relocate::{
    MAX_SHARE, RELOCATION_BIN_LO, RELOCATION_BINS, RELOCATION_BINS_PER_UNIT, RelocationLimits,
    draw, growth_rows, opacity_bin, plan_relocation, relocate_and_grow, relocation,
    relocation_table, weight_table,
};
pub use settings::{MIN_RELOCATION_INTERVAL, McmcReport, McmcSettings, OPACITY_LEARNING_RATE};
pub use step_kernels::McmcKernels;

use super::strategy::{DensifyEvent, DensifyStrategy, StepView};
use crate::gaussians::state::GaussianState;
use anyhow::{Context, Result};
use mcmc_relocate::PendingMcmcRelocate;
use relocate::relocation_seeds;
use trgs_core::rng::Rng;
use trgs_core::scene::Attribute;
use trgs_render::GpuContext;
use trgs_render::toolkit::gpu::Recorder;

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

#[cfg(test)]
mod tests {
    use super::relocate::logit;
    use super::*;
    use crate::gaussians::plan::{TrainState, sigmoid};
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
