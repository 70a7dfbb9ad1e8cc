//! The interface the trainer drives every densification through ([`DensifyStrategy`]), what a
//! strategy sees of a step and what it reports, and the strategy that changes nothing.
use super::classic::settings::{DensifyReport, DensifyStats};
use super::mcmc::settings::McmcReport;
use crate::gaussians::state::GaussianState;
use crate::settings::Stage;
use anyhow::Result;
use trgs_core::pipeline::AdamRate;
use trgs_core::rng::Rng;
use trgs_core::scene::PerAttribute;
use trgs_render::toolkit::gpu::Recorder;
use trgs_render::{Frame, GpuContext, GpuScene, Gradients};

/// What a strategy sees of a step once its backward pass has run.
#[derive(Clone, Copy, Debug)]
pub struct StepView<'a> {
    pub ctx: &'a GpuContext,
    pub scene: &'a GpuScene,
    pub frame: &'a Frame,
    pub grads: &'a Gradients,
    /// The step being taken, counted from 1.
    pub step: u32,
    pub stage: Stage,
    /// The step's learning rates.
    pub rates: &'a PerAttribute<AdamRate>,
    /// The run's seed.
    pub seed: u64,
    /// The step's guard word ([`crate::losses::step_guard`]): the updates a strategy records change
    /// nothing while it is set.
    pub guard: &'a wgpu::Buffer,
}

/// What a strategy did to the set after a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DensifyEvent {
    Densified(DensifyReport),
    Relocated(McmcReport),
    /// Every opacity capped (3DGS's opacity reset).
    OpacityReset,
}

/// One densification strategy, driven by the trainer. The hooks run in this order in a step:
/// [`record_before_adam`](Self::record_before_adam) and
/// [`record_after_adam`](Self::record_after_adam) into the step's Adam batch on the GPU, then
/// [`settle`](Self::settle) (what the last maintenance left pending) and
/// [`maintain`](Self::maintain) once the step's update is recorded.
pub trait DensifyStrategy: std::fmt::Debug + Send + Sync {
    /// A short name for logs ("none", "classic", "mcmc").
    fn name(&self) -> &'static str;

    /// Work recorded before Adam steps the parameters (gradients added by regularisers).
    fn record_before_adam(&self, _step: &StepView<'_>, _rec: &mut Recorder) {}

    /// Work recorded after Adam (statistics of the step, noise on the parameters).
    fn record_after_adam(&self, _step: &StepView<'_>, _rec: &mut Recorder) {}

    /// Edit the set after step `step` (counted from 1) when the schedule says so. A change of
    /// the set's size may be left pending, decided and submitted with its counters on their way
    /// back, for [`settle`](Self::settle) to apply: the trainer settles it at the next step's
    /// maintenance (the GPU runs that step meanwhile), or at once where it must (a step taken
    /// whole, an edit of the set; a checkpoint refuses a pending change).
    fn maintain(
        &mut self,
        step: u32,
        gaussians: &mut GaussianState,
        rng: &mut Rng,
        extent: f64,
    ) -> Result<Vec<DensifyEvent>>;

    /// Apply the change [`maintain`](Self::maintain) left pending, if any (waiting only for its
    /// counters): what it did. The set must not have changed size since.
    fn settle(&mut self, _gaussians: &mut GaussianState) -> Result<Vec<DensifyEvent>> {
        Ok(Vec::new())
    }

    /// Whether a change is pending ([`settle`](Self::settle) would apply it).
    fn pending(&self) -> bool {
        false
    }

    /// Whether step `step` ends with an opacity reset (the perturbation skips those steps).
    fn resets_opacity_at(&self, _step: u32) -> bool {
        false
    }

    /// The set was replaced by one of `n` Gaussians: per-Gaussian state starts over (and a
    /// pending change, decided for the old set, is dropped).
    fn restart(&mut self, _n: usize) {}

    /// The most Gaussians the strategy allows, if it has a bound (MCMC's `--cap`): Gaussians
    /// added from outside it (the planes' seeds) make room within it.
    fn cap(&self) -> Option<usize> {
        None
    }

    /// Per-Gaussian statistics a checkpoint keeps (classic densification's).
    fn statistics(&self) -> Result<Option<DensifyStats>> {
        Ok(None)
    }
}

/// No densification: the count stays as initialised.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoDensification;

impl DensifyStrategy for NoDensification {
    fn name(&self) -> &'static str {
        "none"
    }

    fn maintain(
        &mut self,
        _step: u32,
        _gaussians: &mut GaussianState,
        _rng: &mut Rng,
        _extent: f64,
    ) -> Result<Vec<DensifyEvent>> {
        Ok(Vec::new())
    }
}
