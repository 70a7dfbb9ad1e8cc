//! What a run keeps in its checkpoint besides the trainer's state: its settings, random state,
//! the views still to visit in this epoch, evaluations and clocks.
use super::candidates::{CandidateRecord, PlaneTrial};
use super::checkpoint::Checkpoint;
use super::config::{RunConfig, upgrade_config_record};
use crate::data::TrainingData;
use crate::eval::Evaluation;
use crate::trainer::StepTimes;
use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The run's own state in a checkpoint (under its `extra`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunState {
    /// The run's settings (the key `args` is what checkpoints have always called it).
    #[serde(rename = "args")]
    pub config: RunConfig,
    pub rng_state: u64,
    /// Training views still to visit in this epoch (popped from the back).
    pub order: Vec<usize>,
    pub evaluations: Vec<Evaluation>,
    /// Seconds of training steps so far (not evaluations or checkpoints).
    pub train_seconds: f64,
    /// Wall-clock seconds of the run so far (training, evaluation and checkpoints).
    pub seconds: f64,
    /// Summed milliseconds of each step phase.
    pub phase_ms: StepTimes,
    /// The training views' names, in the order `order` indexes them: a resumed run refuses a
    /// dataset whose views changed (empty in checkpoints that predate it).
    #[serde(default)]
    pub train_views: Vec<String>,
    /// The most GPU memory the trainer held after a step (bytes; 0 in checkpoints that predate
    /// it).
    #[serde(default)]
    pub peak_gpu_bytes: u64,
    /// Steps whose frame outgrew its key list, found after the next step was recorded: they
    /// changed nothing (`StepStats::skipped`).
    #[serde(default)]
    pub skipped_steps: u32,
    /// `--planes auto`: the candidate planes proposed at the end of stage 1 and what became of
    /// them (empty before, and in other runs).
    #[serde(default)]
    pub candidates: Vec<CandidateRecord>,
    /// `--planes auto`: the step the proposal is tried at next (None: proposed, or given up).
    #[serde(default)]
    pub next_proposal: Option<u32>,
    /// `--planes auto`: where stage 1 ended when a later try of the proposal found the
    /// candidates (None: where the schedule ends it).
    #[serde(default)]
    pub stage1_end: Option<u32>,
    /// `--planes auto`: the candidates on trial until they are decided.
    #[serde(default)]
    pub trial: Option<PlaneTrial>,
    /// `--planes auto`: seconds spent proposing and deciding the candidates (part of
    /// `train_seconds`).
    #[serde(default)]
    pub candidate_seconds: f64,
}

impl RunState {
    /// The state a checkpoint holds (settings written by older versions upgraded).
    pub fn of_checkpoint(ck: &Checkpoint, path: &Path) -> Result<Self> {
        let mut extra = ck.extra.clone();
        if let Some(record) = extra.get_mut("args") {
            upgrade_config_record(record);
        }
        serde_json::from_value(extra)
            .with_context(|| format!("{}: the run state is not readable", path.display()))
    }

    /// Refuse to go on with a dataset whose training views are not those the run started with
    /// (`order` indexes them).
    pub fn check_same_views(&self, data: &TrainingData, data_dir: &Path) -> Result<()> {
        let now: Vec<&str> = data.train.iter().map(|v| v.camera.name.as_str()).collect();
        let changed = if self.train_views.is_empty() {
            self.order.iter().any(|&i| i >= now.len())
        } else {
            self.train_views.iter().map(String::as_str).ne(now.iter().copied())
        };
        if changed {
            bail!(
                "--resume: the training views of {} are not those the run started with ({} then, \
                 {} now): restore the dataset, or start a new run",
                data_dir.display(),
                if self.train_views.is_empty() {
                    "unknown".into()
                } else {
                    self.train_views.len().to_string()
                },
                now.len()
            );
        }
        Ok(())
    }
}
