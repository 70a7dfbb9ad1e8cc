//! The training-step measurement of `bench`: whole steps of `Trainer` (render, loss, backward,
//! Adam) at 256x192 on the capture-like room with 100k Gaussians, with their phase breakdown.
use super::common::{median, room_100k, warm_up};
use anyhow::Result;
use trgs_core::fixtures::{RoomDensity, Scene, room_scene};
use trgs_render::{GpuContext, Layer};
use trgs_train::TrainSettings;
use trgs_train::Trainer;
use trgs_train::View;

/// Median times of one configuration's training steps.
pub struct TrainStepRow {
    pub planes: usize,
    pub gaussians: usize,
    pub steps: usize,
    /// Median whole step, wall clock, one step at a time (`Trainer::train_step`: each waits for
    /// its own results).
    pub step_ms: f64,
    /// Wall clock per step of a pipelined loop (each step finished after the next is recorded,
    /// as `train` runs), over `steps` steps, median of three such runs.
    pub pipelined_ms: f64,
    /// Median of each phase (render, loss, backward, adam, readback, densify), wall clock, with
    /// the GPU idle at the end of each (`Trainer::time_phases`).
    pub phases: Vec<(&'static str, f64)>,
    /// Median GPU ms of each stage (timestamp queries) of a profiled step.
    pub stages: Vec<(&'static str, f64)>,
    /// Median GPU ms of a profiled step, every pass's time summed (None without timestamps).
    pub gpu_ms: Option<f64>,
}

/// `steps` timed training steps (after half a second of warm-up) of the joint stage, with the paper's losses
/// and no densification: the target is the scene's own render darkened by 10%, so that every
/// parameter gets a gradient.
pub fn bench_train_step(ctx: &GpuContext, planes: usize, steps: usize) -> Result<TrainStepRow> {
    let scene = room_scene(&room_100k(planes, RoomDensity::AsCaptured));
    let (mut trainer, view) = joint_stage_trainer(ctx, &scene)?;
    warm_up(|| trainer.train_step(&view).map(drop))?;
    let mut totals = Vec::new();
    for _ in 0..steps {
        let t = std::time::Instant::now();
        trainer.train_step(&view)?;
        totals.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let pipelined = (0..3)
        .map(|_| pipelined_step_ms(&mut trainer, &view, steps))
        .collect::<Result<Vec<_>>>()?;
    trainer.time_phases = true;
    let mut phases = vec![Vec::new(); trgs_train::StepTimes::default().phases().len()];
    for _ in 0..steps {
        let s = trainer.train_step(&view)?;
        for (k, (_, ms)) in s.times.phases().into_iter().enumerate() {
            phases[k].push(ms);
        }
    }
    trainer.time_phases = false;
    let profiled = profiled_steps(&mut trainer, &view, steps)?;
    let names = trgs_train::StepTimes::default().phases().map(|(n, _)| n);
    Ok(TrainStepRow {
        planes,
        gaussians: scene.gaussians.len(),
        steps,
        step_ms: median(totals),
        pipelined_ms: median(pipelined),
        phases: names.into_iter().zip(phases.into_iter().map(median)).collect(),
        gpu_ms: profiled.gpu_ms,
        stages: profiled.stages,
    })
}

/// A trainer of `scene` in the joint stage from its first step (every loss and pass of the model
/// on, no perturbation) and the view it trains on: the scene's own render darkened by 10%, so
/// that every parameter gets a gradient.
pub fn joint_stage_trainer(ctx: &GpuContext, scene: &Scene) -> Result<(Trainer, View)> {
    let mut settings = TrainSettings::scaled(30_000);
    settings.stage1 = 0;
    settings.stage2 = 0;
    settings.perturb = None;
    let gaussians = scene.gaussians.cast::<f32>();
    let trainer = Trainer::new(ctx, &gaussians, &scene.planes, settings, 1.0)?;
    let mut image = trainer.render(&scene.camera)?.read_layer(ctx, Layer::Color)?;
    image.data.iter_mut().for_each(|v| *v *= 0.9);
    Ok((trainer, View::new(scene.camera.clone(), image.quantised())))
}

/// Wall clock per step of `steps` steps of a pipelined loop, as `train` runs: each step is
/// finished (read back) after the next is recorded, so that the GPU need not wait for the CPU.
/// The clock starts once the first step is recorded (not while the GPU idles before it).
pub fn pipelined_step_ms(trainer: &mut Trainer, view: &View, steps: usize) -> Result<f64> {
    let mut in_flight = trainer.record_step(view)?;
    let t = std::time::Instant::now();
    for _ in 0..steps {
        let next = trainer.record_step(view)?;
        trainer.maintain()?;
        trainer.finish_step(std::mem::replace(&mut in_flight, next))?;
    }
    let ms = t.elapsed().as_secs_f64() * 1e3 / steps as f64;
    trainer.maintain()?;
    trainer.finish_step(in_flight)?;
    Ok(ms)
}

/// GPU time of profiled steps (timestamp queries around every pass).
pub struct ProfiledSteps {
    /// Median over the steps of each stage's time, summed over the step's views.
    pub stages: Vec<(&'static str, f64)>,
    /// Median over the steps of the step's total, every pass's time summed; None when the
    /// adapter has no timestamp queries.
    pub gpu_ms: Option<f64>,
}

/// `steps` profiled steps. Profiling waits for each submission to read its timestamps back, so
/// these steps are not pipelined; the GPU work they time is the same as a pipelined step's.
pub fn profiled_steps(trainer: &mut Trainer, view: &View, steps: usize) -> Result<ProfiledSteps> {
    trainer.profile = true;
    let stats = (0..steps).map(|_| trainer.train_step(view)).collect::<Result<Vec<_>>>();
    trainer.profile = false;
    let mut samples: Vec<(&'static str, Vec<f64>)> = Vec::new();
    let mut totals = Vec::new();
    for s in stats? {
        // A stage runs once per view (the camera's and each mirrored one): sum per step.
        let mut step: Vec<(&'static str, f64)> = Vec::new();
        for (name, ms) in s.gpu_stages {
            match step.iter_mut().find(|s| s.0 == name) {
                Some(s) => s.1 += ms,
                None => step.push((name, ms)),
            }
        }
        if !step.is_empty() {
            totals.push(step.iter().map(|s| s.1).sum());
        }
        for (name, ms) in step {
            match samples.iter_mut().find(|s| s.0 == name) {
                Some(s) => s.1.push(ms),
                None => samples.push((name, vec![ms])),
            }
        }
    }
    Ok(ProfiledSteps {
        stages: samples.into_iter().map(|(n, v)| (n, median(v))).collect(),
        gpu_ms: (!totals.is_empty()).then(|| median(totals)),
    })
}
