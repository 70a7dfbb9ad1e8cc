//! The scale measurement of `bench --scale`: whole training steps of the capture-like room with
//! one plane (a glass pane) at growing image sizes and Gaussian counts, classic densification
//! on, with the step's time, the time of a step that densifies, and the GPU memory the trainer
//! holds.
use super::common::median;
use super::train_step::{pipelined_step_ms, profiled_steps};
use anyhow::Result;
use std::time::Instant;
use trgs_core::fixtures::{RoomDensity, RoomSpec, room_scene};
use trgs_render::GpuContext;
use trgs_train::GpuMemory;
use trgs_train::densify::{ClassicSettings, Densification};

/// One configuration's measurements.
pub struct ScaleRow {
    pub gaussians: usize,
    /// Median whole step (render, losses, backward, Adam, densification statistics), wall clock.
    pub step_ms: f64,
    /// Wall clock per step of a pipelined loop, as `train` runs (each step read back after the
    /// next is recorded).
    pub pipelined_ms: f64,
    /// Median GPU time of a profiled step: every pass's timestamp-query time summed (None
    /// without timestamps). Over `pipelined_ms`, the share of the wall clock the GPU is busy.
    pub gpu_ms: Option<f64>,
    /// The step that densified (its statistics, decisions and the rebuild of every buffer).
    pub densify_step_ms: f64,
    /// Gaussians after that densification.
    pub densified_to: usize,
    /// The trainer's GPU buffers after the timed steps.
    pub memory: GpuMemory,
    /// The frame's tile keys (every view's).
    pub keys: u64,
}

/// `steps` timed steps (after one untimed) of the joint stage with every loss, a pipelined loop
/// of `steps` steps (one more recorded before its clock starts), `steps` profiled steps, then
/// one step that densifies. The target is the scene's own render darkened by 10%.
pub fn bench_scale(
    ctx: &GpuContext,
    width: u32,
    height: u32,
    gaussians: usize,
    steps: usize,
) -> Result<ScaleRow> {
    let spec = RoomSpec {
        seed: 7,
        gaussians,
        planes: 1,
        width,
        height,
        sh_degree: 3,
        density: RoomDensity::AsCaptured,
    };
    let scene = room_scene(&spec);
    let (mut trainer, view) = super::train_step::joint_stage_trainer(ctx, &scene)?;
    // Statistics every step, the decisions on the step after the measured ones.
    let densify_at = 3 * steps as u32 + 3;
    trainer.set_densification(&Densification::Classic(ClassicSettings {
        from: 0,
        until: u32::MAX,
        every: densify_at,
        opacity_reset_every: u32::MAX,
        max_gaussians: 2 * gaussians,
        ..ClassicSettings::scaled(30_000)
    }))?;
    trainer.train_step(&view)?;
    let mut totals = Vec::new();
    for _ in 0..steps {
        totals.push(trainer.train_step(&view)?.times.total());
    }
    let pipelined_ms = pipelined_step_ms(&mut trainer, &view, steps)?;
    let gpu_ms = profiled_steps(&mut trainer, &view, steps)?.gpu_ms;
    let memory = trainer.gpu_memory();
    let keys = trainer.render(&scene.camera)?.key_count();
    let t = Instant::now();
    let stats = trainer.train_step(&view)?;
    let densify_step_ms = t.elapsed().as_secs_f64() * 1e3;
    anyhow::ensure!(!stats.densified.is_empty(), "step {densify_at} did not densify");
    Ok(ScaleRow {
        gaussians: scene.gaussians.len(),
        step_ms: median(totals),
        pipelined_ms,
        gpu_ms,
        densify_step_ms,
        densified_to: trainer.scene().len() as usize,
        memory,
        keys,
    })
}
