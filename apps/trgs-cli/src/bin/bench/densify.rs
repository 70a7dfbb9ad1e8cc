//! The densification measurement of `bench`: one classic densify-and-prune and one MCMC
//! relocation of the capture-like room's Gaussians (SH degree 3) through the trainer, the set
//! rebuilt on the GPU (`gather_rows`, as training does) and, alternating with it, through the
//! CPU (the whole state read back, rebuilt and uploaded, as training did before).
use crate::median;
use anyhow::Result;
use std::fmt::Write as _;
use std::time::Instant;
use trgs_core::fixtures::{RoomDensity, RoomSpec, room_scene};
use trgs_core::rng::Rng;
use trgs_render::GpuContext;
use trgs_train::densify::classic::plan_densify;
use trgs_train::densify::mcmc::{McmcSettings, plan_relocation};
use trgs_train::densify::{ClassicSettings, DensifyStats, Geometry, RowPlan};
use trgs_train::settings::TrainSettings;
use trgs_train::trainer::Trainer;

/// Median times of one configuration's rebuilds.
pub struct DensifyRow {
    pub kind: &'static str,
    pub gaussians: usize,
    /// Rows of the rebuilt set.
    pub rows: usize,
    pub reps: usize,
    /// Reading the decision attributes back (`Trainer::geometry`).
    pub read_ms: f64,
    /// The CPU's decisions (`plan_densify` / `plan_relocation`).
    pub plan_ms: f64,
    /// The rebuild on the GPU (`Trainer::apply_plan`).
    pub gpu_ms: f64,
    /// The rebuild through the CPU (`Trainer::apply_plan_on_cpu`).
    pub cpu_ms: f64,
}

fn trainer(ctx: &GpuContext, gaussians: usize) -> Result<Trainer> {
    let spec = RoomSpec {
        seed: 7,
        gaussians,
        planes: 1,
        width: 256,
        height: 192,
        sh_degree: 3,
        density: RoomDensity::AsCaptured,
    };
    let scene = room_scene(&spec);
    let settings = TrainSettings::scaled(30_000);
    Trainer::new(ctx, &scene.gaussians.cast::<f32>(), &scene.planes, settings, 1.0)
}

/// Statistics under which about one Gaussian in 20 densifies, as in a capture's early
/// densifications.
fn statistics(n: usize) -> DensifyStats {
    let mut rng = Rng::new(17);
    let mut stats = DensifyStats::new(n);
    for i in 0..n {
        stats.count[i] = 10;
        stats.grad_sum[i] = if rng.uniform() < 0.05 { 3e-3 } else { 1e-3 };
    }
    stats
}

/// Time `reps` rebuilds by `plan` each way, alternating; the set is rebuilt from the same state
/// every time (a plan keeps the row count when applied to its own input's count).
fn time_rebuilds(
    t: &mut Trainer,
    kind: &'static str,
    plan_of: impl Fn(&Geometry) -> RowPlan,
    reps: usize,
) -> Result<DensifyRow> {
    let ctx = t.context().clone();
    let start = t.read_state()?;
    let (mut read, mut planning, mut gpu, mut cpu) = (vec![], vec![], vec![], vec![]);
    let mut rows = 0;
    for _ in 0..reps {
        for on_gpu in [true, false] {
            t.set_state(&start)?;
            trgs_render::toolkit::gpu::wait_for_gpu(&ctx, "the upload")?;
            let clock = Instant::now();
            let geometry = t.geometry()?;
            read.push(clock.elapsed().as_secs_f64() * 1e3);
            let clock = Instant::now();
            let plan = plan_of(&geometry);
            planning.push(clock.elapsed().as_secs_f64() * 1e3);
            rows = plan.sources.len();
            let clock = Instant::now();
            if on_gpu {
                t.apply_plan(&plan)?;
            } else {
                t.apply_plan_on_cpu(&plan)?;
            }
            trgs_render::toolkit::gpu::wait_for_gpu(&ctx, "the rebuild")?;
            let ms = clock.elapsed().as_secs_f64() * 1e3;
            if on_gpu { gpu.push(ms) } else { cpu.push(ms) }
        }
    }
    Ok(DensifyRow {
        kind,
        gaussians: start.gaussians.len(),
        rows,
        reps,
        read_ms: median(read),
        plan_ms: median(planning),
        gpu_ms: median(gpu),
        cpu_ms: median(cpu),
    })
}

pub fn bench_densify(ctx: &GpuContext, gaussians: usize, reps: usize) -> Result<Vec<DensifyRow>> {
    let mut t = trainer(ctx, gaussians)?;
    let n = t.scene().len() as usize;
    let stats = statistics(n);
    let classic = ClassicSettings::scaled(30_000);
    let densify = time_rebuilds(
        &mut t,
        "classic densify-and-prune",
        |g| plan_densify(g, &stats, &classic, 1.0, true, &mut Rng::new(3)).0,
        reps,
    )?;
    let mcmc = McmcSettings::scaled(30_000, 2 * n);
    let relocate = time_rebuilds(
        &mut t,
        "MCMC relocation",
        |g| plan_relocation(g, &mcmc, &mut Rng::new(3)).0,
        reps,
    )?;
    Ok(vec![densify, relocate])
}

pub fn densify_section(s: &mut String, rows: &[DensifyRow]) {
    let _ = writeln!(s, "\n### Densification (capture-like room, SH degree 3, one plane)\n");
    let _ = writeln!(
        s,
        "One densification's rebuild of the Gaussians and their Adam moments, through the trainer: \
         on the GPU (`gather_rows`, as training does) and through the CPU (the whole state read \
         back, rebuilt by the twin `RowPlan::apply` and uploaded), alternating; medians over {} \
         of each. The decisions are the same either way: reading back the attributes they need \
         (`Trainer::geometry`) and planning on the CPU. Classic: statistics under which 5% of the \
         Gaussians densify; MCMC: the room's transparent Gaussians relocated and 5% added.\n",
        rows.first().map_or(0, |r| r.reps)
    );
    let _ = writeln!(
        s,
        "| densification | Gaussians | after | read decisions ms | plan ms | rebuild on the GPU ms | rebuild through the CPU ms | through the CPU / on the GPU |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.2}x |",
            r.kind,
            r.gaussians,
            r.rows,
            r.read_ms,
            r.plan_ms,
            r.gpu_ms,
            r.cpu_ms,
            r.cpu_ms / r.gpu_ms
        );
    }
}
