//! MCMC's relocation and growth as planned on the CPU: the twin of the GPU's `mcmc_relocate`
//! ([`super::mcmc_relocate`]), and the tables and draws the two share. Eq. 9 of the paper gives
//! the opacity and scale of the Gaussians that share one; [`plan_relocation`] makes the plan.
use super::settings::{McmcReport, McmcSettings};
use crate::gaussians::plan::{Geometry, RowPlan, TrainState, sigmoid};
use trgs_core::reference::draw_below;
use trgs_core::rng::Rng;
use trgs_core::scene::Population;

/// The largest number of Gaussians sharing one source in the relocation formula (the binomial
/// sums alternate in sign and lose precision beyond): 50, as the reference code clamps N to
/// `N_max - 1` with its binomial table of `N_max = 51` rows.
pub const MAX_SHARE: usize = 50;

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

pub(super) fn logit(p: f64) -> f32 {
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
    let u = draw_below(seed, j, total);
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
