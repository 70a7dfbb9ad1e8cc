//! How a run is started or resumed, apart from what it trains.
use crate::data::LoadProgress;
use trgs_render::GpuContext;

/// How [`super::TrainingRun::start`] and [`super::TrainingRun::resume`] run, apart from what
/// the run trains (its [`super::RunConfig`], which a resumed run keeps).
#[derive(Default)]
pub struct RunOptions<'a> {
    /// The GPU to train on; None: the best adapter.
    pub context: Option<GpuContext>,
    /// Called as `progress(done, total)` from the loading threads as the photos load.
    pub progress: Option<&'a LoadProgress<'a>>,
    /// `--target-memory` in MiB: the training views' GPU budget on this machine, over the
    /// run's own setting. How the machine holds the work, never what it trains, so a resumed run
    /// takes it too (a run stopped by a lack of GPU memory resumes with a smaller one).
    pub target_memory: Option<u64>,
}

impl std::fmt::Debug for RunOptions<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RunOptions")
            .field("context", &self.context)
            .field("progress", &self.progress.is_some())
            .field("target_memory", &self.target_memory)
            .finish()
    }
}
