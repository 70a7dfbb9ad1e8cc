//! `bench`: renderer benchmarks on the machine's adapter (lavapipe in CI). Renders a room scene
//! (Gaussians on the walls of a box around the camera, see `trgs_core::fixtures::room_scene`) at
//! 256x192 and 512x384 with 10k, 100k and 500k Gaussians and 0, 1 and 2 planes, and reports the
//! wall time of a frame, the GPU time per stage from timestamp queries, the cost ratio of the
//! mirrored passes, the rasterize stage's throughput next to a trivial tiled splat loop, and
//! forward + backward per training-like step (`backward.rs`).
//! `--write FILE` writes the report as Markdown (docs/BENCHMARKS.md).
mod backward;
mod common;
mod densify;
mod host_work;
mod report;
mod scale;
mod throughput;
mod train_step;

use anyhow::Result;
use backward::bench_backward;
use clap::Parser;
use common::{median, room_100k, upload, warm_up};
use densify::bench_densify;
use report::report;
use std::path::PathBuf;
use std::time::Instant;
use throughput::Throughput;
use throughput::{measure_throughput, print_throughput};
use train_step::bench_train_step;
use trgs_core::fixtures::{RoomDensity, RoomSpec};
use trgs_render::{Frame, GpuContext, GpuScene, RenderOptions, Renderer};

/// Renderer benchmarks on this machine's adapter: forward frames over scene sizes and planes,
/// forward + backward, whole training steps and densification.
#[derive(Debug, Parser)]
#[command(name = "bench", version)]
pub struct Args {
    /// Only 256x192 and at most 100k Gaussians
    #[arg(long)]
    quick: bool,
    /// Only the plane-cost measurement (no grid, no throughput, no backward)
    #[arg(long = "plane-cost")]
    plane_cost_only: bool,
    /// Only the backward measurement
    #[arg(long = "backward")]
    backward_only: bool,
    /// Only the training-step measurement (100k Gaussians, phase breakdown)
    #[arg(long = "train-step")]
    train_step_only: bool,
    /// Only the densification measurement (rebuild on the GPU against the CPU)
    #[arg(long = "densify")]
    densify_only: bool,
    /// Only the scale measurement: training steps with one plane and classic densification
    /// over --scale-sizes x --scale-gaussians, with their GPU memory (printed as a Markdown
    /// table; not part of the full run, and not written by --write)
    #[arg(long, conflicts_with = "write")]
    scale: bool,
    /// Only the CPU's work around the GPU's at scale: a 12 MP photo decoded and downscaled, the
    /// SSIM of a 1600x1200 view, a checkpoint and a model.ply of 1M Gaussians written and read
    /// (no GPU needed; not part of the full run, and not written by --write)
    #[arg(long, conflicts_with = "write")]
    host: bool,
    /// Image sizes of --scale
    #[arg(long, value_name = "WxH,...", value_delimiter = ',', requires = "scale", value_parser = trgs_train::run::parse_image_size,
          default_value = "256x192,800x600,1280x960,1600x1200")]
    scale_sizes: Vec<(u32, u32)>,
    /// Gaussian counts of --scale
    #[arg(
        long,
        requires = "scale",
        value_name = "N,...",
        value_delimiter = ',',
        default_value = "100000,300000,1000000,3000000"
    )]
    scale_gaussians: Vec<usize>,
    /// Timed frames per configuration (the median is reported)
    #[arg(long, value_name = "N", default_value_t = 5)]
    reps: usize,
    /// Also write the report as Markdown (e.g. docs/BENCHMARKS.md)
    #[arg(long, value_name = "FILE")]
    write: Option<PathBuf>,
}

struct Row {
    density: RoomDensity,
    width: u32,
    height: u32,
    gaussians: usize,
    planes: usize,
    wall_ms: f64,
    gpu_ms: f64,
    keys: u64,
    stages: Vec<(&'static str, f64)>,
    memory_mb: f64,
}

fn bench_config(
    ctx: &GpuContext,
    renderer: &Renderer,
    spec: &RoomSpec,
    reps: usize,
) -> Result<(Row, Frame)> {
    let (scene, camera) = upload(ctx, spec)?;
    let mut frame = Frame::default();
    let options = RenderOptions::default();
    warm_up(|| renderer.render_into(&scene, &camera, &options, &mut frame))?;
    let mut times = Vec::with_capacity(reps);
    for _ in 0..reps {
        let t = Instant::now();
        renderer.render_into(&scene, &camera, &options, &mut frame)?;
        times.push(t.elapsed().as_secs_f64() * 1e3);
    }
    // Per-stage GPU times: the median of each stage over as many profiled frames.
    let stages = stage_medians(renderer, &scene, &camera, &options, reps, &mut frame)?;
    let row = Row {
        density: spec.density,
        width: spec.width,
        height: spec.height,
        gaussians: spec.gaussians,
        planes: spec.planes,
        wall_ms: median(times),
        gpu_ms: stages.iter().map(|s| s.1).sum(),
        keys: frame.key_count(),
        stages,
        memory_mb: (frame.memory_bytes() as f64) / 1048576.0,
    };
    Ok((row, frame))
}

/// What one plane costs, measured on one scene: frames with the plane enabled and disabled
/// (`RenderOptions::enabled_planes`) alternate, so that the machine's drift hits both alike; the
/// reported ratio is the median over pairs of (with plane) / (without).
struct PlaneCost {
    density: RoomDensity,
    without_ms: f64,
    with_ms: f64,
    ratio: f64,
    pairs: usize,
    /// Median GPU ms per kernel ("stage / kernel"), without and with the plane (profiled
    /// frames alternate too).
    kernels: Vec<(String, f64, f64)>,
}

/// Median GPU time of each stage over `reps` profiled frames.
fn stage_medians(
    renderer: &Renderer,
    scene: &GpuScene,
    camera: &trgs_core::scene::Camera,
    options: &RenderOptions,
    reps: usize,
    frame: &mut Frame,
) -> Result<Vec<(&'static str, f64)>> {
    let stages = |f: &Frame| f.stage_times().unwrap_or_default().to_vec();
    let mut all = medians_alternating(renderer, scene, camera, &[options], reps, frame, stages)?;
    Ok(all.pop().unwrap_or_default())
}

/// Medians of the timings that `timings` takes from a profiled frame, for each of `options`,
/// profiled in turns (each rep renders every option once, starting from a different one each
/// time), so that the machine's drift hits all alike.
fn medians_alternating<K: PartialEq + Clone>(
    renderer: &Renderer,
    scene: &GpuScene,
    camera: &trgs_core::scene::Camera,
    options: &[&RenderOptions],
    reps: usize,
    frame: &mut Frame,
    timings: impl Fn(&Frame) -> Vec<(K, f64)>,
) -> Result<Vec<Vec<(K, f64)>>> {
    let mut samples: Vec<Vec<(K, Vec<f64>)>> = vec![Vec::new(); options.len()];
    for rep in 0..reps {
        for k in 0..options.len() {
            let which = (rep + k) % options.len();
            let profiled = RenderOptions { profile: true, ..options[which].clone() };
            renderer.render_into(scene, camera, &profiled, frame)?;
            for (name, ms) in timings(frame) {
                match samples[which].iter_mut().find(|s| s.0 == name) {
                    Some(s) => s.1.push(ms),
                    None => samples[which].push((name, vec![ms])),
                }
            }
        }
    }
    Ok(samples
        .into_iter()
        .map(|per| per.into_iter().map(|(n, v)| (n, median(v))).collect())
        .collect())
}

fn plane_cost(
    ctx: &GpuContext,
    renderer: &Renderer,
    density: RoomDensity,
    pairs: usize,
) -> Result<PlaneCost> {
    let spec = room_100k(1, density);
    let (scene, camera) = upload(ctx, &spec)?;
    let off = RenderOptions { enabled_planes: vec![false], ..RenderOptions::default() };
    let on = RenderOptions::default();
    let mut frame = Frame::default();
    // Both paths (JIT, buffer pool, clocks).
    warm_up(|| {
        renderer.render_into(&scene, &camera, &on, &mut frame)?;
        renderer.render_into(&scene, &camera, &off, &mut frame)
    })?;
    let (mut without, mut with, mut ratios) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..pairs {
        // Alternate which comes first so that neither always follows the other.
        let order = if i % 2 == 0 { [&off, &on] } else { [&on, &off] };
        let mut t = [0.0; 2];
        for options in order {
            let start = Instant::now();
            renderer.render_into(&scene, &camera, options, &mut frame)?;
            let ms = start.elapsed().as_secs_f64() * 1e3;
            t[usize::from(options.enabled_planes.is_empty())] = ms;
        }
        without.push(t[0]);
        with.push(t[1]);
        ratios.push(t[1] / t[0]);
    }
    let by_kernel = |f: &Frame| {
        let times = f.kernel_times().unwrap_or_default();
        times.iter().map(|k| (format!("{} / {}", k.stage, k.kernel), k.ms)).collect()
    };
    let options = [&off, &on];
    let medians =
        medians_alternating(renderer, &scene, &camera, &options, pairs, &mut frame, by_kernel)?;
    let (base, plane) = (&medians[0], &medians[1]);
    let kernels = plane
        .iter()
        .map(|(n, w)| (n.clone(), base.iter().find(|b| &b.0 == n).map_or(0.0, |b| b.1), *w))
        .collect();
    Ok(PlaneCost {
        density,
        kernels,
        without_ms: median(without),
        with_ms: median(with),
        ratio: median(ratios),
        pairs,
    })
}

pub fn run(matches: &clap::ArgMatches) -> Result<()> {
    let args = super::parsed::<Args>(matches);
    if args.host {
        return host_work::bench_host(args.reps.max(1));
    }
    let ctx = GpuContext::new()?;
    let renderer = Renderer::new(&ctx);
    println!("adapter: {}", ctx.describe());
    if args.scale {
        return run_scale(&ctx, &args);
    }
    let reps = args.reps.max(1);
    let (rows, throughput) = run_forward(&ctx, &renderer, &args)?;
    let backward =
        if args.runs(args.backward_only) { run_backward(&ctx, &renderer, reps)? } else { vec![] };
    let pairs = (3 * args.reps).max(9);
    let costs = if args.runs(args.plane_cost_only) {
        run_plane_costs(&ctx, &renderer, pairs)?
    } else {
        vec![]
    };
    let steps = if args.runs(args.train_step_only) { run_train_steps(&ctx, reps)? } else { vec![] };
    let densify =
        if args.runs(args.densify_only) { run_densify(&ctx, args.quick, reps)? } else { vec![] };
    let measured = report::Measured {
        rows: &rows,
        costs: &costs,
        throughput,
        backward: &backward,
        steps: &steps,
        densify: &densify,
    };
    publish(&ctx, &measured, &args)
}

impl Args {
    /// Whether any `--<measurement>` flag restricts the run to the flagged measurements.
    fn only(&self) -> bool {
        self.plane_cost_only || self.backward_only || self.train_step_only || self.densify_only
    }

    /// Whether the measurement selected by `flag` runs: every one does without an only-flag.
    fn runs(&self, flag: bool) -> bool {
        !self.only() || flag
    }
}

/// The forward grid's configurations (room, width, height, Gaussians): the capture-like room
/// over every size and count, then the uniform room (the worst case for mirrored passes) at
/// 256x192 with 100k Gaussians; none when an only-flag is given.
fn forward_configs(args: &Args) -> Vec<(RoomDensity, u32, u32, usize)> {
    if args.only() {
        return Vec::new();
    }
    let sizes: &[(u32, u32)] = if args.quick { &[(256, 192)] } else { &[(256, 192), (512, 384)] };
    let counts: &[usize] =
        if args.quick { &[10_000, 100_000] } else { &[10_000, 100_000, 500_000] };
    let mut configs = Vec::new();
    for &(width, height) in sizes {
        for &gaussians in counts {
            configs.push((RoomDensity::AsCaptured, width, height, gaussians));
        }
    }
    configs.push((RoomDensity::Uniform, 256, 192, 100_000));
    configs
}

/// Every forward configuration with 0, 1 and 2 planes; the capture-like room at 256x192 with
/// 100k Gaussians and no plane also measures the rasterize throughput on its frame.
fn run_forward(
    ctx: &GpuContext,
    renderer: &Renderer,
    args: &Args,
) -> Result<(Vec<Row>, Option<Throughput>)> {
    let mut rows = Vec::new();
    let mut throughput = None;
    for (density, width, height, gaussians) in forward_configs(args) {
        for planes in 0..=2 {
            let spec =
                RoomSpec { seed: 7, gaussians, planes, width, height, sh_degree: 3, density };
            let (row, frame) = bench_config(ctx, renderer, &spec, args.reps.max(1))?;
            println!(
                "{density:?} {width}x{height} {gaussians:>6} Gaussians {planes} planes: {:8.2} ms wall, {:8.2} ms GPU, {} keys",
                row.wall_ms, row.gpu_ms, row.keys
            );
            let here = (density, width, height, gaussians, planes)
                == (RoomDensity::AsCaptured, 256, 192, 100_000, 0);
            // It times the rasterize stage by GPU timestamps: without them, left out.
            if here && !ctx.capabilities.timestamps {
                println!("no GPU timestamps on this adapter: the rasterize throughput is left out");
            } else if here {
                let rounds = (3 * args.reps).max(9);
                let mut frame = frame;
                let t = measure_throughput(ctx, renderer, &spec, &mut frame, rounds)?;
                print_throughput(&t);
                throughput = Some(t);
            }
            rows.push(row);
        }
    }
    Ok((rows, throughput))
}
/// Forward + backward on both rooms with 0, 1 and 2 planes.
fn run_backward(
    ctx: &GpuContext,
    renderer: &Renderer,
    reps: usize,
) -> Result<Vec<backward::BackwardRow>> {
    let mut backward = Vec::new();
    for density in [RoomDensity::AsCaptured, RoomDensity::Uniform] {
        for planes in 0..=2 {
            let b = bench_backward(ctx, renderer, density, planes, reps)?;
            println!(
                "backward, {density:?} 256x192 100k {planes} planes: forward {:.1} ms, backward {:.1} ms, median ratio {:.2}x",
                b.forward_ms, b.backward_ms, b.ratio
            );
            for (n, ms) in &b.stages {
                println!("    {n:26} {ms:8.2} ms GPU");
            }
            backward.push(b);
        }
    }
    Ok(backward)
}

/// What one plane costs on both rooms, over `pairs` pairs of frames.
fn run_plane_costs(ctx: &GpuContext, renderer: &Renderer, pairs: usize) -> Result<Vec<PlaneCost>> {
    let mut costs = Vec::new();
    for density in [RoomDensity::AsCaptured, RoomDensity::Uniform] {
        let c = plane_cost(ctx, renderer, density, pairs)?;
        println!(
            "plane cost, {density:?} 256x192 100k: {:.1} ms without, {:.1} ms with, median pair ratio {:.3}x over {pairs} pairs",
            c.without_ms, c.with_ms, c.ratio
        );
        for (n, a, b) in &c.kernels {
            println!("    {n:42} {a:8.2} -> {b:8.2} ms GPU");
        }
        costs.push(c);
    }
    Ok(costs)
}

/// Whole training steps with 0 and 1 planes.
fn run_train_steps(ctx: &GpuContext, reps: usize) -> Result<Vec<train_step::TrainStepRow>> {
    let mut steps = Vec::new();
    for planes in 0..=1 {
        let t = bench_train_step(ctx, planes, reps)?;
        println!(
            "training step, 256x192 {} Gaussians {planes} planes: {:.1} ms, pipelined {:.1} ms, GPU {} ms ({} busy; {})",
            t.gaussians,
            t.step_ms,
            t.pipelined_ms,
            report::gpu_ms_cell(t.gpu_ms, 1),
            report::busy_percent(t.gpu_ms, t.pipelined_ms),
            t.phases.iter().map(|(n, ms)| format!("{n} {ms:.1}")).collect::<Vec<_>>().join(", ")
        );
        steps.push(t);
    }
    Ok(steps)
}

/// Densification at 100k Gaussians, and at 300k unless `quick`.
fn run_densify(ctx: &GpuContext, quick: bool, reps: usize) -> Result<Vec<densify::DensifyRow>> {
    let mut densify = Vec::new();
    let sizes: &[usize] = if quick { &[100_000] } else { &[100_000, 300_000] };
    for &gaussians in sizes {
        for r in bench_densify(ctx, gaussians, reps)? {
            println!("{r}");
            densify.push(r);
        }
    }
    Ok(densify)
}

/// Prints the Markdown report, and writes it to `--write`'s file if given.
fn publish(ctx: &GpuContext, measured: &report::Measured<'_>, args: &Args) -> Result<()> {
    let report = report(ctx, measured, args);
    println!("\n{report}");
    if let Some(path) = &args.write {
        trgs_core::io::write_atomic(path, report.as_bytes())?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// `--scale`: each size and count, printed as it is measured and then as one Markdown table.
fn run_scale(ctx: &GpuContext, args: &Args) -> Result<()> {
    use trgs_train::human_bytes;
    let mut lines = vec![
        "| image | Gaussians | keys | step ms | pipelined ms | GPU ms | GPU busy | densify step ms | densified to | parameters | moments | frame | losses | GPU total |".to_string(),
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|".to_string(),
    ];
    for &(width, height) in &args.scale_sizes {
        for &gaussians in &args.scale_gaussians {
            let r = scale::bench_scale(ctx, width, height, gaussians, args.reps.max(1))?;
            let m = &r.memory;
            let line = format!(
                "| {width}x{height} | {} | {} | {:.0} | {:.0} | {} | {} | {:.0} | {} | {} | {} | {} | {} | {} |",
                r.gaussians,
                r.keys,
                r.step_ms,
                r.pipelined_ms,
                report::gpu_ms_cell(r.gpu_ms, 0),
                report::busy_percent(r.gpu_ms, r.pipelined_ms),
                r.densify_step_ms,
                r.densified_to,
                human_bytes(m.parameters),
                human_bytes(m.moments),
                human_bytes(m.frame),
                human_bytes(m.losses),
                human_bytes(m.total())
            );
            println!("{line}");
            lines.push(line);
        }
    }
    println!("\n{}", lines.join("\n"));
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_that_would_be_ignored_are_refused() {
        let parse = |args: &[&str]| Args::try_parse_from([&["bench"], args].concat());
        assert!(parse(&["--quick", "--write", "b.md"]).is_ok());
        assert!(parse(&["--scale", "--scale-sizes", "256x192", "--reps", "2"]).is_ok());
        assert!(parse(&["--scale-sizes", "256x192"]).is_err(), "without --scale");
        assert!(parse(&["--scale-gaussians", "1000"]).is_err(), "without --scale");
        assert!(parse(&["--host", "--write", "b.md"]).is_err(), "--host writes nothing");
        assert!(parse(&["--scale", "--write", "b.md"]).is_err(), "--scale writes nothing");
    }
}
