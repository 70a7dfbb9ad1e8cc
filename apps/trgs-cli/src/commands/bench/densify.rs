//! The densification measurement of `bench`: one classic densify-and-prune and one MCMC
//! relocation of the capture-like room's Gaussians (SH degree 3) through the trainer, three ways
//! in turn: decided and rebuilt on the GPU (`densify_plan` / `mcmc_relocate`, then `gather_rows`,
//! as training does); decided on the CPU from the attributes read back and rebuilt on the GPU
//! (as sets too large for the deciding stages' bindings are); and through the CPU (the whole
//! state read back, rebuilt and uploaded).
use super::common::median;
use anyhow::Result;
use std::fmt::Write as _;
use std::time::Instant;
use trgs_core::fixtures::{RoomDensity, RoomSpec, room_scene};
use trgs_core::rng::Rng;
use trgs_render::GpuContext;
use trgs_train::TrainSettings;
use trgs_train::Trainer;
use trgs_train::densify::classic::plan_densify;
use trgs_train::densify::mcmc::{McmcDensification, McmcSettings, plan_relocation};
use trgs_train::densify::{ClassicDensification, ClassicSettings, DensifyStats};
use trgs_train::stages::{Geometry, RowPlan};

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
    /// Deciding and rebuilding on the GPU (the strategy's own step, as training takes it).
    pub decided_on_gpu_ms: f64,
}

impl std::fmt::Display for DensifyRow {
    /// The progress line of one row.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let r = self;
        write!(
            f,
            "{}, {} -> {} Gaussians: decided and rebuilt on the GPU {:.1} ms; read {:.1} ms, \
             plan {:.1} ms, rebuild on the GPU {:.1} ms, through the CPU {:.1} ms",
            r.kind,
            r.gaussians,
            r.rows,
            r.decided_on_gpu_ms,
            r.read_ms,
            r.plan_ms,
            r.gpu_ms,
            r.cpu_ms
        )
    }
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

/// The strategy's own step on the GPU, as training takes it: the rows after it and its time in
/// ms (deciding and rebuilding, from an idle GPU to an idle GPU; building the strategy and
/// uploading its statistics are not timed).
type GpuStep<'a> = dyn FnMut(&mut Trainer) -> Result<(usize, f64)> + 'a;

/// Time `step` on `t` from an idle GPU to an idle GPU.
fn timed(
    t: &mut Trainer,
    step: impl FnOnce(&mut Trainer) -> Result<usize>,
) -> Result<(usize, f64)> {
    let ctx = t.context().clone();
    trgs_render::toolkit::gpu::wait_for_gpu(&ctx, "the set-up")?;
    let clock = Instant::now();
    let rows = step(t)?;
    trgs_render::toolkit::gpu::wait_for_gpu(&ctx, "the step")?;
    Ok((rows, clock.elapsed().as_secs_f64() * 1e3))
}

/// Time `reps` rebuilds by `plan` each way and `reps` steps of `on_gpu`, in turn; the set is
/// rebuilt from the same state every time (a plan keeps the row count when applied to its own
/// input's count).
fn time_rebuilds(
    t: &mut Trainer,
    kind: &'static str,
    plan_of: impl Fn(&Geometry) -> RowPlan,
    on_gpu: &mut GpuStep<'_>,
    reps: usize,
) -> Result<DensifyRow> {
    let ctx = t.context().clone();
    let start = t.read_state()?;
    let (mut read, mut planning, mut gpu, mut cpu) = (vec![], vec![], vec![], vec![]);
    let mut decided = vec![];
    let mut rows = 0;
    for _ in 0..reps {
        t.set_state(&start)?;
        let (gpu_rows, ms) = on_gpu(t)?;
        decided.push(ms);
        for rebuild_on_gpu in [true, false] {
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
            if rebuild_on_gpu {
                t.apply_plan(&plan)?;
            } else {
                t.apply_plan_on_cpu(&plan)?;
            }
            trgs_render::toolkit::gpu::wait_for_gpu(&ctx, "the rebuild")?;
            let ms = clock.elapsed().as_secs_f64() * 1e3;
            if rebuild_on_gpu { gpu.push(ms) } else { cpu.push(ms) }
        }
        anyhow::ensure!(
            rows == gpu_rows,
            "{kind}: {gpu_rows} rows decided on the GPU, {rows} on the CPU"
        );
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
        decided_on_gpu_ms: median(decided),
    })
}

pub fn bench_densify(ctx: &GpuContext, gaussians: usize, reps: usize) -> Result<Vec<DensifyRow>> {
    let mut t = trainer(ctx, gaussians)?;
    let n = t.scene().len() as usize;
    let stats = statistics(n);
    let classic = ClassicSettings::scaled(30_000);
    let mut strategy = ClassicDensification::resumed(ctx, classic.clone(), n, Some(&stats));
    let mut classic_step = |t: &mut Trainer| {
        strategy.set_statistics(&stats);
        timed(t, |t| {
            t.edit_gaussians(|g, _, extent| {
                strategy.densify_now(g, &mut Rng::new(3), extent, true)?;
                Ok(g.len())
            })
        })
    };
    let densify = time_rebuilds(
        &mut t,
        "classic densify-and-prune",
        |g| plan_densify(g, &stats, &classic, 1.0, true, &mut Rng::new(3)).0,
        &mut classic_step,
        reps,
    )?;
    let mcmc = McmcSettings::scaled(30_000, 2 * n);
    let mut relocation = McmcDensification::new(ctx, mcmc.clone());
    let mut mcmc_step = |t: &mut Trainer| {
        timed(t, |t| {
            t.edit_gaussians(|g, _, _| {
                relocation.relocate_now(g, &mut Rng::new(3))?;
                Ok(g.len())
            })
        })
    };
    let relocate = time_rebuilds(
        &mut t,
        "MCMC relocation",
        |g| plan_relocation(g, &mcmc, &mut Rng::new(3)).0,
        &mut mcmc_step,
        reps,
    )?;
    Ok(vec![densify, relocate])
}

pub fn densify_section(s: &mut String, rows: &[DensifyRow]) {
    let _ = writeln!(s, "\n### Densification (capture-like room, SH degree 3, one plane)\n");
    let _ = writeln!(
        s,
        "One densification through the trainer, three ways in turn, medians over {} of each: \
         decided and rebuilt on the GPU (`densify_plan` / `mcmc_relocate`, then `gather_rows`: \
         what training does); decided on the CPU from the attributes read back \
         (`Trainer::geometry`, then `plan_densify` / `plan_relocation`) and rebuilt on the GPU \
         (what sets too large for the deciding stages' bindings do); and the same decisions \
         with the whole state read back, rebuilt by the twin `RowPlan::apply` and uploaded. \
         Both deciders make the same plan (the bench checks the row counts). Classic: \
         statistics under which 5% of the Gaussians densify; MCMC: the room's transparent \
         Gaussians relocated and 5% added.\n",
        rows.first().map_or(0, |r| r.reps)
    );
    let _ = writeln!(
        s,
        "| densification | Gaussians | after | decided and rebuilt on the GPU ms | read decisions ms | plan on the CPU ms | rebuild on the GPU ms | CPU-decided / GPU-decided | rebuild through the CPU ms |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        let cpu_decided = r.read_ms + r.plan_ms + r.gpu_ms;
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.2}x | {:.1} |",
            r.kind,
            r.gaussians,
            r.rows,
            r.decided_on_gpu_ms,
            r.read_ms,
            r.plan_ms,
            r.gpu_ms,
            cpu_decided / r.decided_on_gpu_ms,
            r.cpu_ms,
        );
    }
}
