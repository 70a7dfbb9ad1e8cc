//! Classic 3DGS densification (Kerbl et al. 2023, section 5.2 and the reference code): Gaussians
//! whose mean moves the image a lot (large average screen-space position gradient) are cloned
//! when small and split in two when large; transparent, huge or screen-filling ones are pruned;
//! opacities are reset to at most 0.01 at intervals. Every `every` steps the decisions are made
//! on the GPU (`densify_plan`, from the statistics and the Gaussians in place; its twin is
//! [`plan_densify`], which also decides for sets too large for the stage's bindings, from a few
//! attributes read back), and the GPU rebuilds every parameter and Adam moment by them
//! (`gather_rows`): survivors keep their moments, new Gaussians start from zero moments, as in
//! the reference code.
pub mod decide;
pub mod densify_plan;
pub mod densify_stats;
pub mod opacity_reset;
pub mod settings;

pub use decide::{densify_and_prune, plan_densify, plan_params};
pub use densify_plan::{DensifyPlanOutput, GpuDensifyPlan};
pub use densify_stats::GpuDensifyStats;
pub use opacity_reset::{GpuOpacityReset, opacity_reset_cap, opacity_reset_logits};
pub use settings::{ClassicSettings, DensifyReport, DensifyStats};

use super::strategy::{DensifyEvent, DensifyStrategy, StepView};
use crate::gaussians::state::GaussianState;
use crate::settings::Stage;
use anyhow::{Context, Result};
use decide::plan_seed;
use densify_plan::PendingDensifyPlan;
use trgs_core::rng::Rng;
use trgs_render::GpuContext;
use trgs_render::toolkit::FrameStages;
use trgs_render::toolkit::gpu::Recorder;

/// Classic densification as a [`DensifyStrategy`]: statistics gathered on the GPU every step,
/// densify and prune every `every` steps, opacity resets.
#[derive(Debug)]
pub struct ClassicDensification {
    ctx: GpuContext,
    settings: ClassicSettings,
    stats: GpuDensifyStats,
    planner: GpuDensifyPlan,
    /// Decide on the GPU where the set fits (see [`ClassicDensification::decide_on_cpu`]).
    on_gpu: bool,
    /// A plan decided on the GPU whose counters are on their way back
    /// ([`DensifyStrategy::settle`]).
    pending: Option<PendingDensifyPlan>,
}

impl ClassicDensification {
    /// For a set of `n` Gaussians, with `stats` (a checkpoint's) or zero statistics.
    pub fn resumed(
        ctx: &GpuContext,
        settings: ClassicSettings,
        n: usize,
        stats: Option<&DensifyStats>,
    ) -> Self {
        let stats = match stats {
            Some(s) => GpuDensifyStats::from_stats(ctx, s),
            None => GpuDensifyStats::new(ctx, n),
        };
        let planner = GpuDensifyPlan::new(ctx);
        Self { ctx: ctx.clone(), settings, stats, planner, on_gpu: true, pending: None }
    }

    pub fn settings(&self) -> &ClassicSettings {
        &self.settings
    }

    /// Densify and prune now, from the statistics gathered since the last time (the schedule
    /// calls it every `every` steps); the statistics start over. Decided on the GPU
    /// (`densify_plan`) when the set fits its bindings, otherwise on the CPU from the few
    /// attributes read back; both draw one seed from `rng` and make the same plan.
    pub fn densify_now(
        &mut self,
        gaussians: &mut GaussianState,
        rng: &mut Rng,
        extent: f64,
        prune_large: bool,
    ) -> Result<DensifyReport> {
        if let Some(report) = self.densify_or_defer(gaussians, rng, extent, prune_large)? {
            return Ok(report);
        }
        self.settle_densify(gaussians)?.context("a densification was planned")
    }

    /// [`ClassicDensification::densify_now`], but a plan decided on the GPU is left pending
    /// (None), for [`ClassicDensification::settle_densify`] to apply once its counters are back.
    fn densify_or_defer(
        &mut self,
        gaussians: &mut GaussianState,
        rng: &mut Rng,
        extent: f64,
        prune_large: bool,
    ) -> Result<Option<DensifyReport>> {
        anyhow::ensure!(self.pending.is_none(), "a densification is already pending");
        let n = gaussians.len();
        let on_gpu = self.on_gpu && GpuDensifyPlan::fits(&self.ctx, n);
        // A growth share below 1 ranks the candidates, which needs their statistics here.
        let stats = if on_gpu && self.settings.grow_fraction >= 1.0 {
            None
        } else {
            Some(self.stats.read(&self.ctx)?)
        };
        if on_gpu {
            let settings = match &stats {
                Some(stats) => self.settings.for_densification(stats),
                None => self.settings.clone(),
            };
            let seed = plan_seed(rng);
            let params = plan_params(&settings, extent, prune_large, n, seed);
            let scene = gaussians.scene();
            self.pending =
                Some(self.planner.record(&self.ctx, scene, self.stats.buffer(), &params)?);
            return Ok(None);
        }
        let stats = stats.context("statistics read back for the CPU's plan")?;
        let geometry = gaussians.geometry()?;
        let (plan, report) =
            plan_densify(&geometry, &stats, &self.settings, extent, prune_large, rng);
        gaussians.apply_plan(&plan)?;
        self.stats.reset(&self.ctx, plan.sources.len());
        Ok(Some(report))
    }

    /// Apply the pending plan, if any: the new set gathered on the GPU, the statistics started
    /// over (those of the steps since it was decided go with the old set).
    fn settle_densify(&mut self, gaussians: &mut GaussianState) -> Result<Option<DensifyReport>> {
        let Some(pending) = self.pending.take() else { return Ok(None) };
        let plan = pending.settle(&self.ctx)?;
        anyhow::ensure!(plan.count() == gaussians.len(), "a densification plan of another set");
        gaussians.apply_densify_plan(&self.planner, &plan)?;
        self.stats.reset(&self.ctx, plan.sources.len() as usize);
        Ok(Some(plan.report))
    }

    /// Replace the statistics gathered so far (a checkpoint's; the benchmark's).
    pub fn set_statistics(&mut self, stats: &DensifyStats) {
        self.stats.upload(&self.ctx, stats);
    }

    /// Decide on the CPU from attributes read back, as sets too large for `densify_plan`'s
    /// bindings are (for tests and `bench --densify`).
    pub fn decide_on_cpu(&mut self) {
        self.on_gpu = false;
    }
}

impl DensifyStrategy for ClassicDensification {
    fn name(&self) -> &'static str {
        "classic"
    }

    fn record_after_adam(&self, step: &StepView<'_>, rec: &mut Recorder) {
        if step.step > self.settings.until {
            return;
        }
        // The camera's pass, and in the joint stage each plane's mirrored pass too (see
        // `DensifyStats::add`). In stage 2 the reflection's gradient does not reach the
        // Gaussians: its passes hold zeros.
        let views = if step.stage == Stage::Joint { step.frame.views().len() } else { 1 };
        self.stats.record_add(step.ctx, rec, step.frame, step.grads, views, step.guard);
    }

    fn maintain(
        &mut self,
        step: u32,
        gaussians: &mut GaussianState,
        rng: &mut Rng,
        extent: f64,
    ) -> Result<Vec<DensifyEvent>> {
        let s = &self.settings;
        let mut events = Vec::new();
        if step > s.from && step < s.until && step.is_multiple_of(s.every) {
            let prune_large = s.prunes_large_at(step);
            // Decided on the GPU, the plan is applied by `settle` (its counters a step late).
            if let Some(report) = self.densify_or_defer(gaussians, rng, extent, prune_large)? {
                events.push(DensifyEvent::Densified(report));
            }
        }
        if self.settings.resets_opacity_at(step) {
            // In place: only the opacities and their moments change, so the statistics
            // gathered since the last densification stay.
            gaussians.opacity_reset(opacity_reset_cap())?;
            events.push(DensifyEvent::OpacityReset);
        }
        Ok(events)
    }

    fn settle(&mut self, gaussians: &mut GaussianState) -> Result<Vec<DensifyEvent>> {
        Ok(self.settle_densify(gaussians)?.map(DensifyEvent::Densified).into_iter().collect())
    }

    fn pending(&self) -> bool {
        self.pending.is_some()
    }

    fn resets_opacity_at(&self, step: u32) -> bool {
        self.settings.resets_opacity_at(step)
    }

    fn restart(&mut self, n: usize) {
        self.pending = None;
        self.stats.reset(&self.ctx, n);
    }

    fn statistics(&self) -> Result<Option<DensifyStats>> {
        Ok(Some(self.stats.read(&self.ctx)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gaussians::plan::{TrainState, sigmoid};
    use trgs_core::scene::{Attribute, Gaussians, PerAttribute, Population, attribute_widths};
    use trgs_render::toolkit::layout::{FLAG_VISIBLE, PROJECTED_GRAD_FLOATS, ProjectedGaussian};

    fn state(n: usize) -> TrainState {
        let mut g = Gaussians::<f32>::empty(0);
        for i in 0..n {
            g.means.push([i as f32, 0.0, 0.0]);
            g.rotations.push([1.0, 0.0, 0.0, 0.0]);
            g.log_scales.push([(0.001f32).ln(); 3]);
            g.opacity_logits.push(0.0);
            g.sh.push([0.1, 0.2, 0.3]);
            g.mask_logits.push(0.0);
            g.log_reflections.push(0.0);
            g.populations.push(Population::Primary);
        }
        let w = attribute_widths(g.sh_coeffs());
        let m = PerAttribute::from_fn(|a| vec![1.0; n * w[a]]);
        let v = PerAttribute::from_fn(|a| vec![2.0; n * w[a]]);
        TrainState { gaussians: g, m, v }
    }

    #[test]
    fn a_step_is_one_observation_summed_over_its_passes() {
        let visible = |on: bool, extent: f32| ProjectedGaussian {
            flags: if on { FLAG_VISIBLE } else { 0 },
            extent: [extent, extent],
            ..ProjectedGaussian::default()
        };
        let grad = |x: f32| {
            let mut g = [0.0f32; PROJECTED_GRAD_FLOATS as usize];
            g[0] = x;
            g
        };
        // Gaussian 0 in both passes, 1 only in the mirrored one, 2 in neither.
        let camera = (
            vec![visible(true, 2.0), visible(false, 0.0), visible(false, 0.0)],
            vec![grad(0.2), grad(0.0), grad(0.0)],
        );
        let mirrored = (
            vec![visible(true, 5.0), visible(true, 3.0), visible(false, 0.0)],
            vec![grad(0.1), grad(0.4), grad(9.0)],
        );
        let mut stats = DensifyStats::new(3);
        stats.add(&[camera, mirrored], 2, 2);
        assert_eq!(stats.count, vec![1, 1, 0]);
        // NDC scale: half the width, 1 here.
        assert!((stats.grad_sum[0] - 0.3).abs() < 1e-7 && (stats.grad_sum[1] - 0.4).abs() < 1e-7);
        assert_eq!(stats.grad_sum[2], 0.0);
        assert_eq!(stats.max_radius, vec![5.0, 3.0, 0.0]);
    }

    #[test]
    fn clone_split_and_prune_by_the_rules() {
        let mut s = state(4);
        s.gaussians.log_scales[1] = [0.0; 3]; // large: splits
        s.gaussians.opacity_logits[3] = -10.0; // transparent: pruned
        let mut stats = DensifyStats::new(4);
        stats.grad_sum = vec![1e-3, 1e-3, 1e-5, 1e-3];
        stats.count = vec![1; 4];
        let settings = ClassicSettings::scaled(30_000);
        let (out, report) = densify_and_prune(&s, &stats, &settings, 1.0, false, &mut Rng::new(1));
        assert_eq!(report, DensifyReport { cloned: 1, split: 1, pruned: 1, seen: 4 });
        // In index order: 0 and its clone, the two children of 1, then 2 (3 is pruned, so not
        // cloned). Survivors keep their moments; the clone and the children restart.
        assert_eq!(out.gaussians.len(), 5);
        let means = &out.m[Attribute::Means];
        assert_eq!(means.len(), 15);
        assert_eq!(&means[..3], &[1.0; 3]);
        assert_eq!(&means[3..12], &[0.0; 9]);
        assert_eq!(&means[12..], &[1.0; 3]);
        assert_eq!(out.gaussians.means[1], [0.0, 0.0, 0.0]);
        assert_eq!(out.gaussians.means[4], [2.0, 0.0, 0.0]);
        for child in [2, 3] {
            let s = out.gaussians.log_scales[child][0];
            assert!((f64::from(s) + 1.6f64.ln()).abs() < 1e-6, "child {child}: {s}");
            assert_ne!(out.gaussians.means[child], [1.0, 0.0, 0.0], "child {child} moved");
        }
    }

    #[test]
    fn pruning_covers_what_densification_makes() {
        let mut s = state(3);
        s.gaussians.log_scales[0] = [(0.5f32).ln(); 3]; // splits; children (0.31) over 0.1 extent
        s.gaussians.log_scales[1] = [(0.1f32).ln(); 3]; // splits; children (0.06) stay
        // 2 is small and clones, but is pruned for its screen size: its clone goes too.
        let mut stats = DensifyStats::new(3);
        stats.grad_sum = vec![1e-3; 3];
        stats.count = vec![1; 3];
        stats.max_radius = vec![1.0, 1.0, 50.0];
        let mut settings = ClassicSettings::scaled(30_000);
        settings.max_screen_radius = 20.0;
        settings.prune_scale = 0.1; // 3DGS's world-size prune (off by default)
        let extent = 2.0;
        let (out, report) =
            densify_and_prune(&s, &stats, &settings, extent, true, &mut Rng::new(1));
        assert_eq!(report, DensifyReport { cloned: 0, split: 2, pruned: 3, seen: 3 });
        assert_eq!(out.gaussians.len(), 3 + 2 - 3);
        for child in &out.gaussians.log_scales {
            assert!((f64::from(child[0]) - (0.1f64 / 1.6).ln()).abs() < 1e-6);
        }
        // With no world-size prune only the screen-size one is left: 2 and its clone go, the
        // children of 0 stay.
        let unbounded = ClassicSettings { prune_scale: f64::INFINITY, ..settings.clone() };
        let (out, report) =
            densify_and_prune(&s, &stats, &unbounded, extent, true, &mut Rng::new(1));
        assert_eq!(report, DensifyReport { cloned: 0, split: 2, pruned: 1, seen: 3 });
        assert_eq!(out.gaussians.len(), 3 + 2 - 1);
        // Without the size prune (before the first reset) all of it stays.
        let (out, report) =
            densify_and_prune(&s, &stats, &settings, extent, false, &mut Rng::new(1));
        assert_eq!(report, DensifyReport { cloned: 1, split: 2, pruned: 0, seen: 3 });
        assert_eq!(out.gaussians.len(), 6);
    }

    #[test]
    fn a_growth_share_raises_the_threshold_to_its_last_candidate() {
        let mut s = state(10);
        // Gaussian 9 is transparent: ranked, then left out.
        s.gaussians.opacity_logits[9] = -10.0;
        let mut stats = DensifyStats::new(10);
        // Averages 1e-4 (under the threshold), then 3e-4 ... 1.1e-3 over two observations.
        stats.count = vec![2; 10];
        stats.grad_sum =
            (0..10).map(|i| 2.0 * if i == 0 { 1e-4 } else { (i + 2) as f64 * 1e-4 }).collect();
        let mut settings = ClassicSettings::scaled(30_000);
        let densified = |s: &TrainState, settings: &ClassicSettings| {
            let (_, r) = densify_and_prune(s, &stats, settings, 1.0, false, &mut Rng::new(1));
            r.cloned + r.split
        };
        // All eight opaque candidates (1 to 8).
        assert_eq!(densified(&s, &settings), 8);
        assert_eq!(settings.for_densification(&stats), settings);
        // Three of the nine candidates: 7, 8 and the transparent 9.
        settings.grow_fraction = 1.0 / 3.0;
        assert_eq!(densified(&s, &settings), 2);
        // A share rounds up to whole candidates: 0.01 of nine is the largest one.
        settings.grow_fraction = 0.01;
        assert_eq!(densified(&s, &settings), 0);
        s.gaussians.opacity_logits[9] = 0.0;
        assert_eq!(densified(&s, &settings), 1);
        // No candidates: nothing to rank.
        let none = DensifyStats::new(10);
        assert_eq!(settings.for_densification(&none).grad_threshold, settings.grad_threshold);
    }

    #[test]
    fn reset_caps_opacity() {
        let mut logits = vec![5.0, -6.0];
        opacity_reset_logits(&mut logits);
        assert!((sigmoid(f64::from(logits[0])) - 0.01).abs() < 1e-6);
        assert_eq!(logits[1], -6.0);
    }

    #[test]
    fn resets_come_while_densification_goes_on() {
        let at = |s: &ClassicSettings| (0..=s.until).filter(|&t| s.resets_opacity_at(t)).collect();
        // 3DGS at 30k steps: 3000, 6000, 9000, 12000 (densification stops at 15000).
        let resets: Vec<u32> = at(&ClassicSettings::scaled(30_000));
        assert_eq!(resets, vec![3000, 6000, 9000, 12000]);
        // At least ten densifications apart: one at 4000 steps, none at 2000.
        assert_eq!(at(&ClassicSettings::scaled(4000)), vec![1000]);
        assert_eq!(at(&ClassicSettings::scaled(2000)), Vec::<u32>::new());
        let never = ClassicSettings { opacity_reset_every: 0, ..ClassicSettings::scaled(30_000) };
        assert_eq!(at(&never), Vec::<u32>::new());
    }

    #[test]
    fn the_world_size_prune_starts_after_the_first_reset_and_never_without_one() {
        let s = ClassicSettings::scaled(30_000);
        assert!(!s.prunes_large_at(2900) && !s.prunes_large_at(3000) && s.prunes_large_at(3100));
        let never = ClassicSettings { opacity_reset_every: 0, ..s };
        assert!((0..=30_000).step_by(100).all(|t| !never.prunes_large_at(t)));
    }
}
