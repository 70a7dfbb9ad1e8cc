//! What a finished run writes into its folder: model.ply, planes.json, the test renders and
//! their layers, metrics.json, and with `--exposure on` exposures.json (each training view's
//! learned affine colour); each file written to a temporary name and renamed into place.
use super::state::RunState;
use crate::data::TrainingData;
use crate::densify::Densification;
use crate::eval::{Evaluation, Renderable, TruthComparison, compare_with_truth};
use crate::eval::{render_fps, write_renders};
use crate::trainer::Trainer;
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};
use trgs_core::io::{EvaluationPoint, ViewScore, write_atomic, write_planes_json, write_ply};
use trgs_core::pipeline::ReflectionModel;

/// The outcome of a finished run.
#[derive(Clone, Debug)]
pub struct RunSummary {
    /// The run folder.
    pub out: PathBuf,
    pub steps: u32,
    /// Seconds of training steps (not evaluations or checkpoints).
    pub train_seconds: f64,
    /// The last evaluation (the test views, or the first training views without a test split).
    pub last: Evaluation,
    pub gaussians: u32,
    pub planes: usize,
    /// Mean milliseconds of each step phase.
    pub step_ms: Vec<(&'static str, f64)>,
    /// Frames per second of the evaluation views.
    pub render_fps: f64,
    /// For a synthetic scene: the planes, transmission and regions against its ground truth.
    pub truth: Option<TruthComparison>,
    /// The ground truth's folder, when there is one.
    pub truth_dir: Option<PathBuf>,
    /// The trainer's GPU buffers at the end, by what they hold.
    pub gpu_memory: crate::trainer::memory::GpuMemory,
}

/// What outputs and evaluation need of the trainer.
pub fn model_of(trainer: &Trainer) -> Renderable<'_> {
    Renderable {
        ctx: trainer.context(),
        renderer: trainer.renderer(),
        scene: trainer.scene(),
        options: trainer.render_options(),
    }
}

/// The final evaluation and outputs of a run into `state.config.out`.
pub fn write_outputs(
    trainer: &Trainer,
    data: &TrainingData,
    data_dir: &Path,
    state: &RunState,
) -> Result<RunSummary> {
    let config = &state.config;
    let last = state.evaluations.last().cloned().context("no evaluation was made")?;
    let model = model_of(trainer);
    let truth = compare_with_truth(&model, trainer.planes(), data, data_dir)?;
    let steps = f64::from(trainer.step.max(1));
    let step_ms: Vec<(&str, f64)> =
        state.phase_ms.phases().iter().map(|&(k, v)| (k, v / steps)).collect();
    let out = &config.out;
    let gaussians = trainer.gaussians()?;
    // A model other tools cannot read (a NaN, a zero quaternion) is not written as one.
    trgs_core::scene::validate_gaussians(&gaussians)
        .context("the trained model is not valid, so model.ply was not written")?;
    write_ply(&out.join("model.ply"), &gaussians)?;
    write_planes_json(&out.join("planes.json"), trainer.planes())?;
    write_renders(&model, data, &out.join("renders"))?;
    let fps = render_fps(&model, data)?;
    let summary = RunSummary {
        out: out.clone(),
        steps: trainer.step,
        train_seconds: state.train_seconds,
        last,
        gaussians: trainer.scene().len(),
        planes: trainer.planes().len(),
        step_ms,
        render_fps: fps,
        truth_dir: truth.is_some().then(|| data_dir.join("gt")),
        truth,
        gpu_memory: trainer.gpu_memory(),
    };
    if config.exposure.is_on() {
        // Every training view, those never drawn with the identity they start from.
        let views: serde_json::Map<_, _> = data
            .train
            .iter()
            .map(|v| &v.camera.name)
            .map(|name| (name.clone(), serde_json::json!(trainer.exposures().matrix(name))))
            .collect();
        let exposures = serde_json::json!({
            "what": "per training view: C' = M [r g b 1]^T, a 3x4 matrix applied to the render",
            "views": views,
        });
        let text = serde_json::to_string_pretty(&exposures)?;
        write_atomic(&out.join("exposures.json"), text.as_bytes())?;
    }
    let metrics = metrics_json(&summary, data, state);
    write_atomic(&out.join("metrics.json"), serde_json::to_string_pretty(&metrics)?.as_bytes())?;
    Ok(summary)
}

fn metrics_json(s: &RunSummary, data: &TrainingData, state: &RunState) -> serde_json::Value {
    let config = &state.config;
    let last = &s.last;
    // The parts other tools read back are written from the types they read (`RunMetrics`).
    let views: Vec<_> = last
        .views
        .iter()
        .map(|(name, psnr, ssim)| ViewScore { name: name.clone(), psnr: *psnr, ssim: *ssim })
        .collect();
    let step_ms: serde_json::Map<_, _> =
        s.step_ms.iter().map(|(k, v)| (k.to_string(), serde_json::json!(v))).collect();
    let over_time: Vec<_> = state
        .evaluations
        .iter()
        .map(|e| EvaluationPoint { step: e.step, seconds: e.seconds, psnr: e.psnr, ssim: e.ssim })
        .collect();
    let ab = &config.ablations;
    let reflection = ReflectionModel { fresnel: !ab.no_fresnel, intensity: !ab.no_intensity };
    serde_json::json!({
        "psnr": last.psnr,
        "ssim": last.ssim,
        "right_half": last.right_half,
        "exposure": config.exposure,
        "eval_views": data.eval_views_name(),
        "views": views,
        "train_seconds": s.train_seconds,
        "step_ms": step_ms,
        "steps": s.steps,
        "skipped_steps": state.skipped_steps,
        "gaussians": s.gaussians,
        "planes": s.planes,
        "render_fps": s.render_fps,
        "resolution": [data.size().0, data.size().1],
        "ablations": ab.names(),
        "densification": densification_json(&config.densification()),
        "reflection_model": reflection,
        "data": config.data,
        "no_planes": config.no_planes || config.planes == Some(super::PlaneSource::None),
        "plane_source": config.planes,
        "candidates": state.candidates,
        "candidate_seconds": state.candidate_seconds,
        "truth": s.truth,
        "psnr_over_time": over_time,
        "memory": {
            "peak_gpu_bytes": state.peak_gpu_bytes,
            "gpu_bytes": s.gpu_memory,
            "peak_ram_bytes": crate::trainer::memory::peak_ram_bytes(),
        },
    })
}

/// The densification's knobs as the run used them, so that runs told apart by a flag are told
/// apart by their metrics too.
fn densification_json(densification: &Densification) -> serde_json::Value {
    match densification {
        Densification::None => serde_json::json!({ "mode": "none" }),
        Densification::Classic(s) => serde_json::json!({
            "mode": "classic",
            "grow_fraction": s.grow_fraction,
            "opacity_reset_every": s.opacity_reset_every,
            // null: never (JSON has no infinity).
            "prune_scale": s.prune_scale.is_finite().then_some(s.prune_scale),
        }),
        Densification::Mcmc(s) => serde_json::json!({ "mode": "mcmc", "cap": s.cap }),
    }
}
