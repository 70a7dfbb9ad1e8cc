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
use trgs_core::scene::Camera;

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
    /// The training views' cameras as loaded ([`camera_records`]): a resumed run refuses views
    /// whose cameras changed under the same names (a COLMAP model made again, in a frame of its
    /// own). Empty in checkpoints that predate it.
    #[serde(default)]
    pub train_cameras: Vec<CameraRecord>,
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
    /// (`order` indexes them), or whose cameras moved or changed lens.
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
        if let Some(i) = first_changed_camera(&self.train_cameras, &camera_records(data)) {
            bail!(
                "--resume: the camera of the training view {} in {} is not the one the run \
                 started with (its pose or lens changed: was the COLMAP model made again?): \
                 restore the dataset, or start a new run",
                now[i],
                data_dir.display()
            );
        }
        Ok(())
    }
}

/// A camera as a resumed run compares it: fx, fy, cx, cy, the world-to-camera rotation
/// (columns) and translation.
pub type CameraRecord = [f64; 16];

/// The training views' cameras, in the order `order` indexes them.
pub fn camera_records(data: &TrainingData) -> Vec<CameraRecord> {
    data.train.iter().map(|v| camera_record(&v.camera)).collect()
}

fn camera_record(camera: &Camera) -> CameraRecord {
    let k = &camera.intrinsics;
    let r = camera.pose.rotation.to_cols_array();
    let t = camera.pose.translation;
    let mut record = [0.0; 16];
    record[..4].copy_from_slice(&[k.fx, k.fy, k.cx, k.cy]);
    record[4..13].copy_from_slice(&r);
    record[13..].copy_from_slice(&t.to_array());
    record
}

/// The first camera of `now` that differs from `then`'s (None where `then` is empty: a
/// checkpoint that predates the records). Loading the same files gives the same numbers, so the
/// tolerance only forgives rounding a later build may do differently.
fn first_changed_camera(then: &[CameraRecord], now: &[CameraRecord]) -> Option<usize> {
    let close = |a: &CameraRecord, b: &CameraRecord| {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-6 * (1.0 + x.abs().max(y.abs())))
    };
    if then.is_empty() {
        return None;
    }
    then.iter().zip(now).position(|(a, b)| !close(a, b))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DMat3, DVec3};
    use trgs_core::scene::{Intrinsics, Pose};

    fn camera(x: f64, fx: f64) -> Camera {
        let k = Intrinsics { fx, fy: fx, cx: 32.0, cy: 24.0, width: 64, height: 48 };
        let pose =
            Pose { rotation: DMat3::from_rotation_y(0.3), translation: DVec3::new(x, 0.5, 4.0) };
        Camera::new("a.png", k, pose)
    }

    #[test]
    fn a_camera_moved_or_refocused_is_found_and_rounding_is_not() {
        let then: Vec<_> =
            [camera(0.0, 60.0), camera(1.0, 60.0)].iter().map(camera_record).collect();
        let same: Vec<_> =
            [camera(0.0, 60.0), camera(1.0 + 1e-12, 60.0)].iter().map(camera_record).collect();
        assert_eq!(first_changed_camera(&then, &same), None);
        let moved: Vec<_> =
            [camera(0.0, 60.0), camera(1.01, 60.0)].iter().map(camera_record).collect();
        assert_eq!(first_changed_camera(&then, &moved), Some(1));
        let lens: Vec<_> =
            [camera(0.0, 61.0), camera(1.0, 60.0)].iter().map(camera_record).collect();
        assert_eq!(first_changed_camera(&then, &lens), Some(0));
        assert_eq!(first_changed_camera(&[], &moved), None, "an older checkpoint: names only");
    }
}
