//! Classic 3DGS densification (Kerbl et al. 2023, section 5.2 and the reference code): Gaussians
//! whose mean moves the image a lot (large average screen-space position gradient) are cloned
//! when small and split in two when large; transparent, huge or screen-filling ones are pruned;
//! opacities are reset to at most 0.01 at intervals. Every `every` steps the decisions are made
//! on the CPU from a few attributes read back ([`Geometry`]) into a [`RowPlan`], which the GPU
//! carries out over every parameter and Adam moment (`gather_rows`): survivors keep their
//! moments, new Gaussians start from zero moments, as in the reference code.
use super::{DensifyEvent, DensifyStrategy, Geometry, RowPlan, StepView, TrainState, sigmoid};
use crate::densify_stats::GpuDensifyStats;
use crate::gaussian_state::GaussianState;
use crate::settings::{Stage, scale_len};
use anyhow::Result;
use glam::{DMat3, DQuat, DVec3};
use trgs_core::rng::Rng;
use trgs_render::GpuContext;
use trgs_render::toolkit::FrameStages;
use trgs_render::toolkit::gpu::Recorder;
use trgs_render::toolkit::layout::{FLAG_VISIBLE, PROJECTED_GRAD_FLOATS, ProjectedGaussian};

/// The schedule and thresholds (3DGS defaults for 30k steps; lengths scale with the run).
#[derive(Clone, Debug, PartialEq)]
pub struct ClassicSettings {
    pub from: u32,
    pub until: u32,
    pub every: u32,
    pub opacity_reset_every: u32,
    /// Average norm of dL/d(mean in NDC) above which a Gaussian densifies.
    pub grad_threshold: f64,
    /// Fraction of the scene extent separating clone (smaller) from split (larger).
    pub percent_dense: f64,
    pub min_opacity: f64,
    /// Prune Gaussians whose screen radius exceeds this (pixels), after the first reset
    /// (infinite: no screen-size prune).
    pub max_screen_radius: f64,
    /// Never grow beyond this many Gaussians.
    pub max_gaussians: usize,
}

impl ClassicSettings {
    /// The start and end scale with the run; the interval does not (the statistics need about a
    /// hundred views' gradients each time, whatever the run's length), and the opacity reset comes
    /// at least ten densifications apart, so runs of 2000 steps or fewer have none: resets three
    /// densifications apart (steps 300 and 600 of 2000) leave a short run no time to recover,
    /// and plain 3DGS ended lower on the synthetic scenes with them.
    pub fn scaled(iterations: u32) -> Self {
        let every = 100;
        Self {
            from: scale_len(500, iterations),
            until: scale_len(15_000, iterations),
            every,
            opacity_reset_every: scale_len(3000, iterations).max(10 * every),
            grad_threshold: 2e-4,
            percent_dense: 0.01,
            min_opacity: 0.005,
            // Off, as in effect in the references: INRIA's code zeroes the radii just before its
            // prune, so its 20-pixel test never fires, and gsplat disables it by default. A fixed
            // pixel radius would also mean a different share of the image at each resolution.
            max_screen_radius: f64::INFINITY,
            max_gaussians: 1_000_000,
        }
    }

    /// Whether step `t` ends with an opacity reset: every `opacity_reset_every` steps while
    /// densification goes on (3DGS: 3000 ... 12000 of 15000).
    pub fn resets_opacity_at(&self, t: u32) -> bool {
        t > 0 && t < self.until && t.is_multiple_of(self.opacity_reset_every)
    }
}

/// Per-Gaussian statistics gathered between densification steps.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DensifyStats {
    /// Per Gaussian, the sum over its observations of its screen-space gradient norm (in NDC).
    pub grad_sum: Vec<f64>,
    /// Steps in which a pass saw the Gaussian.
    pub count: Vec<u32>,
    /// The largest screen radius in pixels it had.
    pub max_radius: Vec<f64>,
}

impl DensifyStats {
    pub fn new(n: usize) -> Self {
        Self { grad_sum: vec![0.0; n], count: vec![0; n], max_radius: vec![0.0; n] }
    }

    /// Add one step's screen-space gradients of an image `width x height` (the twin of the GPU's
    /// `densify_stats`, which training uses): the camera's pass, then
    /// any mirrored passes (whose images are the camera's). A Gaussian seen in any pass counts as
    /// one observation whose gradient is the sum of its passes' norms, as its mean's gradient is
    /// the sum of theirs: averaged as separate views, the faint reflection would dilute what the
    /// camera's pass measures, and a surface seen mostly in a reflection (the room behind the
    /// cameras) would be densified only from the few views that see it directly.
    pub fn add(
        &mut self,
        passes: &[(Vec<ProjectedGaussian>, Vec<[f32; PROJECTED_GRAD_FLOATS as usize]>)],
        width: u32,
        height: u32,
    ) {
        let (hw, hh) = (0.5 * f64::from(width), 0.5 * f64::from(height));
        for i in 0..self.count.len() {
            let mut seen = false;
            for (projected, grads) in passes {
                let (Some(p), Some(g)) = (projected.get(i), grads.get(i)) else { continue };
                if p.flags & FLAG_VISIBLE == 0 {
                    continue;
                }
                seen = true;
                // 3DGS measures the gradient in NDC: d/d(ndc) = d/d(pixel) * size / 2.
                let (gx, gy) = (f64::from(g[0]) * hw, f64::from(g[1]) * hh);
                self.grad_sum[i] += (gx * gx + gy * gy).sqrt();
                let r = f64::from(p.extent[0].max(p.extent[1]));
                self.max_radius[i] = self.max_radius[i].max(r);
            }
            if seen {
                self.count[i] += 1;
            }
        }
    }
}

/// What one densification step did: the count went from n to n + cloned + split - pruned (a
/// split replaces one Gaussian by two; children pruned at once count as pruned).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DensifyReport {
    pub cloned: usize,
    pub split: usize,
    pub pruned: usize,
}

/// Classic densification as a [`DensifyStrategy`]: statistics gathered on the GPU every step,
/// densify and prune every `every` steps, opacity resets.
#[derive(Debug)]
pub struct ClassicDensification {
    ctx: GpuContext,
    settings: ClassicSettings,
    stats: GpuDensifyStats,
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
        Self { ctx: ctx.clone(), settings, stats }
    }

    pub fn settings(&self) -> &ClassicSettings {
        &self.settings
    }

    /// Densify and prune now, from the statistics gathered since the last time (the schedule
    /// calls it every `every` steps); the statistics start over.
    pub fn densify_now(
        &mut self,
        gaussians: &mut GaussianState,
        rng: &mut Rng,
        extent: f64,
        prune_large: bool,
    ) -> Result<DensifyReport> {
        let stats = self.stats.read(&self.ctx)?;
        let geometry = gaussians.geometry()?;
        let (plan, report) =
            plan_densify(&geometry, &stats, &self.settings, extent, prune_large, rng);
        gaussians.apply_plan(&plan)?;
        self.stats.reset(&self.ctx, plan.sources.len());
        Ok(report)
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
            let prune_large = step > s.opacity_reset_every;
            let report = self.densify_now(gaussians, rng, extent, prune_large)?;
            events.push(DensifyEvent::Densified(report));
        }
        if self.settings.resets_opacity_at(step) {
            // In place: only the opacities and their moments change, so the statistics
            // gathered since the last densification stay.
            gaussians.reset_opacities(cap_opacity_logits)?;
            events.push(DensifyEvent::OpacityReset);
        }
        Ok(events)
    }

    fn resets_opacity_at(&self, step: u32) -> bool {
        self.settings.resets_opacity_at(step)
    }

    fn restart(&mut self, n: usize) {
        self.stats.reset(&self.ctx, n);
    }

    fn statistics(&self) -> Result<Option<DensifyStats>> {
        Ok(Some(self.stats.read(&self.ctx)?))
    }
}

/// One densify-and-prune step (3DGS's `densify_and_prune`) on the CPU: [`plan_densify`], then
/// [`RowPlan::apply`].
pub fn densify_and_prune(
    state: &TrainState,
    stats: &DensifyStats,
    settings: &ClassicSettings,
    extent: f64,
    prune_large: bool,
    rng: &mut Rng,
) -> (TrainState, DensifyReport) {
    let geometry = Geometry::of(&state.gaussians);
    let (plan, report) = plan_densify(&geometry, stats, settings, extent, prune_large, rng);
    (plan.apply(state), report)
}

/// The plan of one densify-and-prune step: survivors, clones and split children, with the
/// children's means and scales.
pub fn plan_densify(
    g: &Geometry,
    stats: &DensifyStats,
    settings: &ClassicSettings,
    extent: f64,
    prune_large: bool,
    rng: &mut Rng,
) -> (RowPlan, DensifyReport) {
    let n = g.len();
    let max_scale = |i: usize| {
        let s = g.log_scales[i];
        f64::from(s[0].max(s[1]).max(s[2])).exp()
    };
    let mut report = DensifyReport::default();
    let mut room = settings.max_gaussians.saturating_sub(n);
    let transparent = |i: usize| sigmoid(f64::from(g.opacity_logits[i])) < settings.min_opacity;
    let prune = |i: usize| {
        transparent(i)
            || (prune_large
                && (stats.max_radius[i] > settings.max_screen_radius
                    || max_scale(i) > 0.1 * extent))
    };
    let mut clone = vec![false; n];
    let mut split = vec![false; n];
    for i in 0..n {
        // A transparent Gaussian is neither cloned nor split: 3DGS prunes the new Gaussians too,
        // and they inherit the opacity.
        if stats.count[i] == 0 || room == 0 || transparent(i) {
            continue;
        }
        let avg = stats.grad_sum[i] / f64::from(stats.count[i]);
        if !(avg >= settings.grad_threshold) {
            continue;
        }
        if max_scale(i) <= settings.percent_dense * extent {
            clone[i] = true;
            report.cloned += 1;
        } else {
            split[i] = true;
            report.split += 1;
        }
        room -= 1;
    }
    // Survivors (split parents are replaced by their children), then clones, then children.
    let mut sources: Vec<(usize, bool)> = Vec::with_capacity(n + report.cloned + 2 * report.split);
    for i in 0..n {
        if split[i] || prune(i) {
            if !split[i] {
                report.pruned += 1;
            }
            continue;
        }
        sources.push((i, true));
    }
    // A clone of a Gaussian pruned for its screen size would only bring it back.
    let clones: Vec<usize> = (0..n).filter(|&i| clone[i] && !prune(i)).collect();
    report.cloned = clones.len();
    sources.extend(clones.into_iter().map(|i| (i, false)));
    let first_child = sources.len();
    // 3DGS prunes after densifying, over the new Gaussians too: children still over the
    // world-size limit go at once (a clone is small by construction, so none is).
    let child_too_large = |i: usize| prune_large && max_scale(i) / 1.6 > 0.1 * extent;
    let parents: Vec<usize> = (0..n).filter(|&i| split[i] && !child_too_large(i)).collect();
    report.pruned += 2 * (report.split - parents.len());
    for &i in &parents {
        sources.push((i, false));
        sources.push((i, false));
    }
    let mut means: Vec<[f32; 3]> = sources.iter().map(|&(i, _)| g.means[i]).collect();
    let mut log_scales: Vec<[f32; 3]> = sources.iter().map(|&(i, _)| g.log_scales[i]).collect();
    // Children: means drawn from the parent's Gaussian, scales divided by 0.8 N (N = 2).
    for (c, &i) in parents.iter().enumerate() {
        let q = g.rotations[i].map(f64::from);
        let rot = DMat3::from_quat(DQuat::from_xyzw(q[1], q[2], q[3], q[0]).normalize());
        let s = g.log_scales[i].map(|v| f64::from(v).exp());
        let mean = DVec3::from_array(g.means[i].map(f64::from));
        for k in 0..2 {
            let j = first_child + 2 * c + k;
            let local = DVec3::new(s[0] * rng.normal(), s[1] * rng.normal(), s[2] * rng.normal());
            let p = mean + rot * local;
            means[j] = p.to_array().map(|v| v as f32);
            log_scales[j] = g.log_scales[i].map(|v| (f64::from(v) - (0.8f64 * 2.0).ln()) as f32);
        }
    }
    let plan =
        RowPlan { sources, means: Some(means), log_scales: Some(log_scales), opacity_logits: None };
    (plan, report)
}

/// 3DGS's opacity reset of the logits: every opacity becomes at most 0.01.
pub fn cap_opacity_logits(logits: &mut [f32]) {
    let cap = (0.01f64 / 0.99).ln() as f32;
    for o in logits {
        *o = o.min(cap);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use trgs_core::scene::{Attribute, Gaussians, PerAttribute, Population, attribute_widths};

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
        assert_eq!(report, DensifyReport { cloned: 1, split: 1, pruned: 1 });
        // Survivors 0, 2; the clone of 0 (3 is pruned, so not cloned); two children of 1.
        assert_eq!(out.gaussians.len(), 5);
        let means = &out.m[Attribute::Means];
        assert_eq!(means.len(), 15);
        assert_eq!(&means[..6], &[1.0; 6]);
        assert_eq!(&means[6..], &[0.0; 9]);
        assert_eq!(out.gaussians.means[2], [0.0, 0.0, 0.0]);
        let child = out.gaussians.log_scales[3][0];
        assert!((f64::from(child) + 1.6f64.ln()).abs() < 1e-6);
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
        let extent = 2.0;
        let (out, report) =
            densify_and_prune(&s, &stats, &settings, extent, true, &mut Rng::new(1));
        assert_eq!(report, DensifyReport { cloned: 0, split: 2, pruned: 3 });
        assert_eq!(out.gaussians.len(), 3 + 2 - 3);
        for child in &out.gaussians.log_scales {
            assert!((f64::from(child[0]) - (0.1f64 / 1.6).ln()).abs() < 1e-6);
        }
        // Without the size prune (before the first reset) all of it stays.
        let (out, report) =
            densify_and_prune(&s, &stats, &settings, extent, false, &mut Rng::new(1));
        assert_eq!(report, DensifyReport { cloned: 1, split: 2, pruned: 0 });
        assert_eq!(out.gaussians.len(), 6);
    }

    #[test]
    fn reset_caps_opacity() {
        let mut logits = vec![5.0, -6.0];
        cap_opacity_logits(&mut logits);
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
    }
}
