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
//! There is no pruning and no opacity reset. Glass Gaussians are never moved, sampled or noised:
//! they belong to their plane.
use super::{DensifyEvent, DensifyStrategy, Geometry, RowPlan, StepView, TrainState, sigmoid};
use crate::gaussian_state::GaussianState;
use crate::kernels::TRAINING_KERNELS;
use crate::layout::McmcParams;
use crate::mcmc_relocate::GpuMcmcRelocate;
use crate::settings::scale_len;
use anyhow::Result;
use trgs_core::reference::{AdamRate, pcg_hash};
use trgs_core::rng::Rng;
use trgs_core::scene::{Attribute, Population};
use trgs_render::toolkit::gpu::{self, Kernel, Recorder, grid_1d, range};
use trgs_render::{GpuContext, GpuScene, SceneGradBuffers};

/// The largest number of Gaussians sharing one source in the relocation formula (the binomial
/// sums alternate in sign and lose precision beyond): 50, as the reference code clamps N to
/// `N_max - 1` with its binomial table of `N_max = 51` rows.
pub const MAX_SHARE: usize = 50;

/// The shortest relocation interval in steps (each relocation waits for its counters and
/// rebuilds every buffer: several steps' time, `bench --densify`).
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
    /// relocations, each a wait for its counters and a rebuild, in very short runs): growing 5% per relocation, a run then reaches its cap at
    /// the same fraction of its length as the paper's run does. A fixed floor of 20 steps made a
    /// 2000-step run reach its cap at 64% of the run, where classic densification has its count
    /// at 50%, and MCMC trained with about half as many Gaussians until then.
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

/// Eq. 9 of the paper: the opacity and the scale factor of each of `share` Gaussians that replace
/// one of opacity `opacity` (at most [`MAX_SHARE`] are accounted for).
pub fn relocation(opacity: f64, share: usize, min_opacity: f64) -> (f64, f64) {
    let n = share.clamp(1, MAX_SHARE);
    // The scale comes from the unclamped opacity and only the opacity is clamped afterwards, as
    // in the reference (its kernel, then `_update_params`); the floor keeps the sum non-zero.
    let new_o = (1.0 - (1.0 - opacity).powf(1.0 / n as f64)).max(f64::MIN_POSITIVE);
    let mut denom = 0.0;
    for i in 1..=n {
        let mut binom = 1.0;
        for k in 0..i {
            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
            denom += binom * sign * new_o.powi(k as i32 + 1) / ((k + 1) as f64).sqrt();
            binom = binom * (i - 1 - k) as f64 / (k + 1) as f64;
        }
    }
    (new_o.clamp(min_opacity, 1.0 - 1e-7), opacity / denom)
}

fn logit(p: f64) -> f32 {
    (p / (1.0 - p)).ln() as f32
}

/// Opacity bins of relocation: logits in [-16, 16) at 1/64, clamped at both ends. Relocation
/// draws in proportion to a bin's opacity and applies Eq. 9 from a table by bin, so that the GPU
/// (`mcmc_relocate`) and the twin make the same draws and write the same bits: both compute a
/// bin with one correctly rounded subtraction and an exact multiplication, where a sigmoid or
/// Eq. 9's alternating sums would round differently on each side. A bin spans a 1/64 step of the
/// logit: the opacity at its centre is within 0.8% of any in it.
pub const RELOCATION_BINS: u32 = 2048;
pub const RELOCATION_BIN_LO: f32 = -16.0;
pub const RELOCATION_BINS_PER_UNIT: f32 = 64.0;

/// The bin of an opacity logit.
pub fn opacity_bin(logit: f32) -> u32 {
    let x = ((logit - RELOCATION_BIN_LO) * RELOCATION_BINS_PER_UNIT).floor();
    x.clamp(0.0, (RELOCATION_BINS - 1) as f32) as u32
}

/// The opacity at the centre of bin `b`.
fn bin_opacity(b: u32) -> f64 {
    sigmoid(
        f64::from(RELOCATION_BIN_LO) + (f64::from(b) + 0.5) / f64::from(RELOCATION_BINS_PER_UNIT),
    )
}

/// Eq. 9 by bin and share: entry `b * (MAX_SHARE - 1) + share - 2` holds the logit of the new
/// opacity (before the clamp into [min_opacity, 1 - 1e-7], which [`RelocationLimits`] applies)
/// and the log of the scale factor, for `share` Gaussians (2 ..= MAX_SHARE) replacing one of bin
/// `b`'s opacity. Built once (about 2000 x 49 evaluations of [`relocation`]).
pub fn relocation_table() -> &'static [[f32; 2]] {
    static TABLE: std::sync::OnceLock<Vec<[f32; 2]>> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let mut t = Vec::with_capacity(RELOCATION_BINS as usize * (MAX_SHARE - 1));
        for b in 0..RELOCATION_BINS {
            for share in 2..=MAX_SHARE {
                // No clamp here: the floor keeps the logit finite, the limits clamp it later.
                let (o, factor) = relocation(bin_opacity(b), share, 0.0);
                t.push([logit(o.min(1.0 - 1e-12)), factor.ln() as f32]);
            }
        }
        t
    })
}

/// Where the relocated opacities are clamped, as logits, and which are dead.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RelocationLimits {
    /// Logits at or below this are dead.
    pub dead_logit: f32,
    pub min_logit: f32,
    pub max_logit: f32,
}

impl RelocationLimits {
    pub fn new(min_opacity: f64) -> Self {
        let dead = logit(min_opacity);
        Self { dead_logit: dead, min_logit: dead, max_logit: logit(1.0 - 1e-7) }
    }

    /// The table's entry for `share` Gaussians replacing one of logit `l`: the new logit
    /// (clamped) and the log scale factor.
    pub fn share(&self, l: f32, share: usize) -> (f32, f32) {
        let index = opacity_bin(l) as usize * (MAX_SHARE - 1) + share.clamp(2, MAX_SHARE) - 2;
        let [new, ln_factor] = relocation_table()[index];
        (new.clamp(self.min_logit, self.max_logit), ln_factor)
    }
}

/// Integer draw weights by bin for a set of `n`: each bin's opacity in units of 2^-S, with S as
/// large as keeps the sum over `n` Gaussians within a u32 (the GPU's scan), at least 1 so that
/// every candidate can be drawn. S is 12 at 1M Gaussians: the faintest live opacity (0.005) is
/// then weighted within 3%.
pub fn weight_table(n: usize) -> Vec<u32> {
    let s = (f64::from(u32::MAX) / n.max(1) as f64).log2().floor().clamp(0.0, 24.0);
    let unit = 2f64.powf(s);
    (0..RELOCATION_BINS).map(|b| ((bin_opacity(b) * unit).round() as u32).max(1)).collect()
}

/// Draw `j` of a relocation with seed `seed`, from weights whose exclusive scan is `cumulative`
/// with sum `total` (> 0): the last index whose cumulative weight is at most a uniform integer
/// below `total`, which has a non-zero weight. Integer arithmetic: the GPU draws the same.
pub fn draw(seed: u32, j: u32, cumulative: &[u32], total: u32) -> usize {
    let r = pcg_hash(j ^ pcg_hash(seed));
    let u = ((u64::from(r) * u64::from(total)) >> 32) as u32;
    cumulative.partition_point(|&c| c <= u) - 1
}

/// The exclusive scan of `w` and its total.
fn exclusive_scan(w: &[u32]) -> (Vec<u32>, u32) {
    let mut total = 0u32;
    let scan = w
        .iter()
        .map(|&x| {
            let before = total;
            total += x;
            before
        })
        .collect();
    (scan, total)
}

/// `count` draws among the rows whose weight `w` is non-zero (none when all are zero).
fn draws(seed: u32, w: &[u32], count: usize) -> Vec<usize> {
    let (cumulative, total) = exclusive_scan(w);
    if total == 0 {
        return Vec::new();
    }
    (0..count as u32).map(|j| draw(seed, j, &cumulative, total)).collect()
}

/// Give each source of `counts` (copies it receives) its share's opacity and scale, and mark its
/// moments to restart.
fn apply_shares(rows: &mut Rows, counts: &[(usize, usize)], limits: &RelocationLimits) {
    for &(src, copies) in counts {
        let (l, ln_factor) = limits.share(rows.opacity_logits[src], copies + 1);
        rows.opacity_logits[src] = l;
        rows.log_scales[src] = rows.log_scales[src].map(|s| s + ln_factor);
        rows.sources[src].1 = false;
    }
}

/// The relocation's working rows: per row, the input Gaussian it copies and whether its moments
/// stay, with the attributes relocation changes.
struct Rows {
    sources: Vec<(usize, bool)>,
    opacity_logits: Vec<f32>,
    log_scales: Vec<[f32; 3]>,
    populations: Vec<Population>,
}

impl Rows {
    /// Row `to` becomes a copy of row `from`, with restarting moments.
    fn copy(&mut self, to: usize, from: usize) {
        self.sources[to] = (self.sources[from].0, false);
        self.opacity_logits[to] = self.opacity_logits[from];
        self.log_scales[to] = self.log_scales[from];
        self.populations[to] = self.populations[from];
    }

    fn primary(&self, i: usize) -> bool {
        self.populations[i] == Population::Primary
    }

    /// The draw weights of the rows (primary ones, that `alive` accepts).
    fn weights(&self, table: &[u32], alive: impl Fn(usize) -> bool) -> Vec<u32> {
        (0..self.sources.len())
            .map(|i| {
                let live = self.primary(i) && alive(i);
                if live { table[opacity_bin(self.opacity_logits[i]) as usize] } else { 0 }
            })
            .collect()
    }
}

/// How many times each index occurs in `draws`, as (index, count) in index order.
fn tally(draws: &[usize]) -> Vec<(usize, usize)> {
    let mut sorted = draws.to_vec();
    sorted.sort_unstable();
    let mut out: Vec<(usize, usize)> = Vec::new();
    for i in sorted {
        match out.last_mut() {
            Some((j, c)) if *j == i => *c += 1,
            _ => out.push((i, 1)),
        }
    }
    out
}

/// One relocation step: move the dead primary Gaussians onto live ones, then grow by `growth` up
/// to `cap` (3DGS-MCMC's `relocate_gs` and `add_new_gs`).
pub fn relocate_and_grow(
    state: &TrainState,
    settings: &McmcSettings,
    rng: &mut Rng,
) -> (TrainState, McmcReport) {
    let (plan, report) = plan_relocation(&Geometry::of(&state.gaussians), settings, rng);
    (plan.apply(state), report)
}

/// How many Gaussians a relocation step of a set of `n` adds (growth up to the cap).
pub fn growth_rows(settings: &McmcSettings, n: usize) -> usize {
    let target = ((settings.growth * n as f64) as usize).min(settings.cap);
    target.saturating_sub(n)
}

/// The seeds of one relocation step's two rounds of draws (two draws of the run's generator, on
/// the GPU and in the twin alike).
pub(crate) fn relocation_seeds(rng: &mut Rng) -> [u32; 2] {
    [rng.next_u64() as u32, rng.next_u64() as u32]
}

/// The plan of one relocation step, the twin of the GPU's `mcmc_relocate` ([`relocate_and_grow`]
/// runs it on the CPU): the rows it copies, with every row's opacity and scale. Dead primary
/// Gaussians (logit at or below min_opacity's) take copies of live primary ones drawn in
/// proportion to their opacity; then the set grows by `growth` (up to `cap`) with copies of
/// primary Gaussians drawn by their new opacities. A Gaussian that receives N - 1 copies and its
/// copies all take Eq. 9's opacity and scale for N.
pub fn plan_relocation(
    g: &Geometry,
    settings: &McmcSettings,
    rng: &mut Rng,
) -> (RowPlan, McmcReport) {
    let n = g.len();
    let [seed_relocate, seed_grow] = relocation_seeds(rng);
    let limits = RelocationLimits::new(settings.min_opacity);
    let table = weight_table(n);
    let mut rows = Rows {
        sources: (0..n).map(|i| (i, true)).collect(),
        opacity_logits: g.opacity_logits.clone(),
        log_scales: g.log_scales.clone(),
        populations: g.populations.clone(),
    };
    let dead_at = |l: f32| l <= limits.dead_logit;
    let dead: Vec<usize> =
        (0..n).filter(|&i| rows.primary(i) && dead_at(rows.opacity_logits[i])).collect();
    let alive = rows.weights(&table, |i| !dead_at(g.opacity_logits[i]));
    let sources = draws(seed_relocate, &alive, dead.len());
    apply_shares(&mut rows, &tally(&sources), &limits);
    // Each dead slot becomes a copy of its (updated) source, with zero moments.
    for (&d, &src) in dead.iter().zip(&sources) {
        rows.copy(d, src);
    }
    let relocated = sources.len();
    // Growth: sample among every primary Gaussian by its (new) opacity.
    let candidates = rows.weights(&table, |_| true);
    let added_from = draws(seed_grow, &candidates, growth_rows(settings, n));
    apply_shares(&mut rows, &tally(&added_from), &limits);
    for &i in &added_from {
        rows.sources.push((i, true));
        rows.opacity_logits.push(0.0);
        rows.log_scales.push([0.0; 3]);
        rows.populations.push(Population::Primary);
        let last = rows.sources.len() - 1;
        rows.copy(last, i);
    }
    let plan = RowPlan {
        sources: rows.sources,
        means: None,
        log_scales: Some(rows.log_scales),
        opacity_logits: Some(rows.opacity_logits),
    };
    (plan, McmcReport { relocated, added: added_from.len() })
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
}

impl McmcDensification {
    pub fn new(ctx: &GpuContext, settings: McmcSettings) -> Self {
        Self {
            ctx: ctx.clone(),
            settings,
            kernels: McmcKernels::new(ctx),
            relocation: GpuMcmcRelocate::new(ctx),
            on_gpu: true,
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
        let (n, growth) = (gaussians.len(), growth_rows(&self.settings, gaussians.len()));
        if !(self.on_gpu && GpuMcmcRelocate::fits(&self.ctx, n, growth)) {
            let (plan, report) = plan_relocation(&gaussians.geometry()?, &self.settings, rng);
            gaussians.apply_plan(&plan)?;
            return Ok(report);
        }
        let limits = RelocationLimits::new(self.settings.min_opacity);
        let seeds = relocation_seeds(rng);
        let scene = gaussians.scene();
        let plan = self.relocation.plan(&self.ctx, scene, &limits, growth as u32, seeds)?;
        gaussians.apply_mcmc_relocate(&plan)?;
        Ok(plan.report)
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
        Ok(vec![DensifyEvent::Relocated(self.relocate_now(gaussians, rng)?)])
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
    use super::*;
    use trgs_core::scene::{Gaussians, PerAttribute};

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
