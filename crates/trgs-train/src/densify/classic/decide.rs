//! Classic densification's decisions on the CPU: the twin of the GPU's `densify_plan`
//! ([`super::densify_plan`]), which also decides for sets too large for that stage's bindings.
//! Both compare the same f32 values ([`plan_params`]) by the same rules, so they make the same
//! plan.
use super::settings::{ClassicSettings, DensifyReport, DensifyStats};
use crate::gaussians::plan::{Geometry, RowPlan, TrainState};
use crate::layout::DensifyPlanParams;
use glam::{DMat3, DQuat, DVec3};
use trgs_core::reference::noise_normal;
use trgs_core::rng::Rng;

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

/// Classic densification's thresholds for a set of `n` Gaussians, as the f32 values that the
/// GPU's `densify_plan` and its twin [`plan_densify`] both compare: an opacity as its logit, a
/// world size as a log scale, the average gradient as a product (`sum >= threshold * count`),
/// so that no rounding of an exp, a sigmoid or a quotient can tell the two apart.
pub fn plan_params(
    settings: &ClassicSettings,
    extent: f64,
    prune_large: bool,
    n: usize,
    seed: u32,
) -> DensifyPlanParams {
    let m = settings.min_opacity;
    DensifyPlanParams {
        count: n as u32,
        room: settings.max_gaussians.saturating_sub(n).min(u32::MAX as usize) as u32,
        prune_large: u32::from(prune_large),
        seed,
        grad_threshold: settings.grad_threshold as f32,
        transparent_logit: (m / (1.0 - m)).ln() as f32,
        clone_log_scale: (settings.percent_dense * extent).ln() as f32,
        prune_log_scale: log_scale_or_max(settings.prune_scale * extent),
        // A child's scale is its parent's over 1.6: over the prune's size when the parent's is
        // over 1.6 times it.
        child_prune_log_scale: log_scale_or_max(1.6 * settings.prune_scale * extent),
        // f32::MAX for "off" (infinite): WGSL may assume no infinities.
        max_screen_radius: (settings.max_screen_radius as f32).min(f32::MAX),
        child_log_shrink: 1.6f64.ln() as f32,
        pad0: 0,
    }
}

/// The log of a world size as the plan compares it, kept finite (WGSL may assume no
/// infinities): f32::MAX for an infinite size, so that nothing is over it.
fn log_scale_or_max(size: f64) -> f32 {
    (size.ln() as f32).clamp(f32::MIN, f32::MAX)
}

/// What becomes of one Gaussian (the twin of `densify_plan_rows`' decision).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Fate {
    /// It stays, with its Adam moments.
    survivor: bool,
    clone: bool,
    /// It densifies by splitting (counted even when its children are pruned at once).
    split: bool,
    /// Its two children are kept.
    children: bool,
    /// How many the step prunes of it and its children.
    pruned: usize,
}

/// The rules of shaders/shared/densify_rules.wgsl and densify_plan_rows.wgsl on the CPU.
struct Rules<'a> {
    p: &'a DensifyPlanParams,
    g: &'a Geometry,
    stats: &'a DensifyStats,
}

impl Rules<'_> {
    fn transparent(&self, i: usize) -> bool {
        self.g.opacity_logits[i] < self.p.transparent_logit
    }

    fn candidate(&self, i: usize) -> bool {
        let (sum, count) = (self.stats.grad_sum[i] as f32, self.stats.count[i] as f32);
        count > 0.0 && !self.transparent(i) && sum >= self.p.grad_threshold * count
    }

    fn max_log_scale(&self, i: usize) -> f32 {
        let s = self.g.log_scales[i];
        s[0].max(s[1]).max(s[2])
    }

    /// Gaussian `i`'s fate, `rank` being the number of candidates before it.
    fn fate(&self, i: usize, rank: u32) -> Fate {
        let p = self.p;
        let size = self.max_log_scale(i);
        let large = p.prune_large != 0;
        let prune = self.transparent(i)
            || (large
                && (self.stats.max_radius[i] as f32 > p.max_screen_radius
                    || size > p.prune_log_scale));
        let densify = self.candidate(i) && rank < p.room;
        let split = densify && size > p.clone_log_scale;
        let children = split && !(large && size > p.child_prune_log_scale);
        Fate {
            survivor: !split && !prune,
            clone: densify && !split && !prune,
            split,
            children,
            pruned: usize::from(!split && prune) + if split && !children { 2 } else { 0 },
        }
    }
}

/// The plan of one densify-and-prune step, the twin of the GPU's `densify_plan`: each Gaussian
/// in index order makes its rows of the new set, its survivor (keeping its moments), its clone,
/// or the two children that replace it when it splits, with the children's means and scales.
/// Densification is decided in index order while `max_gaussians` leaves room; a transparent
/// Gaussian is neither cloned nor split (3DGS prunes the new ones too, and they inherit its
/// opacity); a Gaussian pruned for its size is not cloned (the clone would only bring it back);
/// split children still over the world-size limit are pruned at once (3DGS prunes after
/// densifying). The children's means are the parent's plus R (s * z), z drawn by
/// `noise_normal` numbered 2 i + k from a seed drawn from `rng`. `settings` are the run's: a
/// growth share below 1 is applied here ([`ClassicSettings::for_densification`]), so that no
/// caller can leave it out.
pub fn plan_densify(
    g: &Geometry,
    stats: &DensifyStats,
    settings: &ClassicSettings,
    extent: f64,
    prune_large: bool,
    rng: &mut Rng,
) -> (RowPlan, DensifyReport) {
    let n = g.len();
    let settings = settings.for_densification(stats);
    let p = plan_params(&settings, extent, prune_large, n, plan_seed(rng));
    let rules = Rules { p: &p, g, stats };
    let mut report = DensifyReport::default();
    let mut sources: Vec<(usize, bool)> = Vec::with_capacity(n);
    let mut means: Vec<[f32; 3]> = Vec::with_capacity(n);
    let mut log_scales: Vec<[f32; 3]> = Vec::with_capacity(n);
    let mut rank = 0u32;
    for i in 0..n {
        let fate = rules.fate(i, rank);
        rank += u32::from(rules.candidate(i));
        report.cloned += usize::from(fate.clone);
        report.split += usize::from(fate.split);
        report.pruned += fate.pruned;
        // The sum as the GPU holds it (f32).
        report.seen += usize::from(stats.grad_sum[i] as f32 > 0.0);
        // The survivor keeps its moments; the clone restarts them.
        for (made, keep) in [(fate.survivor, true), (fate.clone, false)] {
            if made {
                sources.push((i, keep));
                means.push(g.means[i]);
                log_scales.push(g.log_scales[i]);
            }
        }
        if !fate.children {
            continue;
        }
        let q = g.rotations[i].map(f64::from);
        let rot = DMat3::from_quat(DQuat::from_xyzw(q[1], q[2], q[3], q[0]).normalize());
        let s = DVec3::from_array(g.log_scales[i].map(|v| f64::from(v).exp()));
        let mean = DVec3::from_array(g.means[i].map(f64::from));
        for k in 0..2u32 {
            let item = 2 * i as u32 + k;
            let z = DVec3::from_array([0, 1, 2].map(|c| noise_normal(p.seed, item, c)));
            sources.push((i, false));
            means.push((mean + rot * (s * z)).to_array().map(|v| v as f32));
            log_scales.push(g.log_scales[i].map(|v| v - p.child_log_shrink));
        }
    }
    let plan =
        RowPlan { sources, means: Some(means), log_scales: Some(log_scales), opacity_logits: None };
    (plan, report)
}

/// The seed of one densification's random draws (one draw of the run's generator, on the GPU
/// and in the twin alike).
pub(crate) fn plan_seed(rng: &mut Rng) -> u32 {
    rng.next_u64() as u32
}
