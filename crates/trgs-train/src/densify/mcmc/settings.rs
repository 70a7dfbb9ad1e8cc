//! What MCMC densification is set with and what each relocation reports: the values its
//! strategy, its GPU stages and its twin share.
use crate::settings::scale_len;

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
