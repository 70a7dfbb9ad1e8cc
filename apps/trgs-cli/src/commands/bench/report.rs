//! The Markdown report of `bench`: every measurement's table, with the command that made it.
use super::backward::BackwardRow;
use super::densify::{DensifyRow, densify_section};
use super::throughput::Throughput;
use super::train_step::TrainStepRow;
use super::{Args, PlaneCost, Row};
use std::fmt::Write as _;
use trgs_core::fixtures::RoomDensity;
use trgs_render::GpuContext;

fn density_name(d: RoomDensity) -> &'static str {
    match d {
        RoomDensity::AsCaptured => "as captured",
        RoomDensity::Uniform => "uniform",
    }
}

/// Every measurement of one run.
pub struct Measured<'a> {
    pub rows: &'a [Row],
    pub costs: &'a [PlaneCost],
    pub throughput: Option<Throughput>,
    pub backward: &'a [BackwardRow],
    pub steps: &'a [TrainStepRow],
    pub densify: &'a [DensifyRow],
}

pub fn report(ctx: &GpuContext, m: &Measured<'_>, args: &Args) -> String {
    let mut s = String::new();
    intro(&mut s, ctx, args);
    if !m.rows.is_empty() {
        forward_section(&mut s, m.rows);
    }
    if !m.costs.is_empty() {
        plane_cost_section(&mut s, m.costs);
    }
    if !m.rows.is_empty() {
        forward_stages_section(&mut s, m.rows);
    }
    if let Some(t) = m.throughput.as_ref() {
        throughput_section(&mut s, t);
    }
    if !m.backward.is_empty() {
        backward_section(&mut s, m.backward);
    }
    if !m.steps.is_empty() {
        train_step_section(&mut s, m.steps);
    }
    if !m.densify.is_empty() {
        densify_section(&mut s, m.densify);
    }
    s
}

/// The command line that reproduces this run, flags in a fixed order.
fn bench_command(args: &Args) -> String {
    format!(
        "trgs bench --reps {}{}{}{}{}{}{}",
        args.reps,
        if args.quick { " --quick" } else { "" },
        if args.plane_cost_only { " --plane-cost" } else { "" },
        if args.backward_only { " --backward" } else { "" },
        if args.train_step_only { " --train-step" } else { "" },
        if args.densify_only { " --densify" } else { "" },
        args.write.as_ref().map_or(String::new(), |p| format!(" --write {}", p.display()))
    )
}

/// The title, the command and adapter, and what the scene and the columns are.
fn intro(s: &mut String, ctx: &GpuContext, args: &Args) {
    let cmd = bench_command(args);
    let _ = writeln!(s, "## Renderer benchmarks\n");
    let _ = writeln!(s, "Made by `{cmd}` on {}.", ctx.describe());
    let _ = writeln!(
        s,
        "Scene: `trgs_core::fixtures::room_scene`: Gaussians on the walls of a room around the camera, SH degree 3; \
         plane 0 a glass pane, plane 1 a mirror, each covering at most a quarter of the image (1% of the Gaussians are \
         glass Gaussians on them). *As captured*: every surface has Gaussians of about constant screen size in the view \
         that sees it best (the camera's, or a mirrored view through a plane), as 3DGS densification leaves a capture. \
         *Uniform*: the same world-space density on every wall; a mirror then sees the room behind the camera from \
         farther away, about 3.5x denser on screen than the transmitted view: the worst case for mirrored passes. \
         Wall: median of {} frames, CPU encoding and the one readback of key totals included. \
         GPU: sum over stages of the median of each stage's timestamp-query time over as many profiled frames.\n",
        args.reps
    );
}

/// One row per forward configuration; "vs no plane" divides by the same room, image and
/// Gaussian count without planes.
fn forward_section(s: &mut String, rows: &[Row]) {
    let _ = writeln!(s, "### Forward\n");
    let _ = writeln!(
        s,
        "| room | image | Gaussians | planes | wall ms | frames/s | GPU ms | vs no plane | keys | frame memory MiB |"
    );
    let _ = writeln!(s, "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        let base = rows
            .iter()
            .find(|b| {
                b.density == r.density
                    && b.width == r.width
                    && b.gaussians == r.gaussians
                    && b.planes == 0
            })
            .map_or(f64::NAN, |b| b.wall_ms);
        let _ = writeln!(
            s,
            "| {} | {}x{} | {} | {} | {:.1} | {:.0} | {:.1} | {:.2}x | {} | {:.1} |",
            density_name(r.density),
            r.width,
            r.height,
            r.gaussians,
            r.planes,
            r.wall_ms,
            1e3 / r.wall_ms,
            r.gpu_ms,
            r.wall_ms / base,
            r.keys,
            r.memory_mb
        );
    }
}

/// The with/without table of every room, then each room's kernel table.
fn plane_cost_section(s: &mut String, costs: &[PlaneCost]) {
    let _ = writeln!(s, "\n### What one plane costs (256x192, 100k Gaussians)\n");
    let _ = writeln!(
        s,
        "One scene with one plane whose footprint is a quarter of the image, rendered with the plane \
         disabled and enabled (`RenderOptions::enabled_planes`) in alternating frames, so the Gaussians \
         and the transmitted pass are identical and the machine's drift hits both alike. Ratio: the \
         median over pairs of (with plane) / (without). The issue's bound is 1.25x; the paper's \
         implementation, which renders the mirrored view over the whole image, costs 1.5x.\n"
    );
    let _ = writeln!(s, "| room | pairs | without plane ms | with plane ms | ratio |");
    let _ = writeln!(s, "|---|---:|---:|---:|---:|");
    for c in costs {
        let _ = writeln!(
            s,
            "| {} | {} | {:.1} | {:.1} | {:.2}x |",
            density_name(c.density),
            c.pairs,
            c.without_ms,
            c.with_ms,
            c.ratio
        );
    }
    for c in costs {
        plane_kernel_table(s, c);
    }
}

/// Where one room's plane time goes: each kernel without and with the plane, and their sums.
fn plane_kernel_table(s: &mut String, c: &PlaneCost) {
    let _ = writeln!(
        s,
        "\nWhere the plane's time goes, {} room: median GPU ms of each kernel within its \
         stage over {} profiled frames of each kind, in turns.\n",
        density_name(c.density),
        c.pairs
    );
    let _ = writeln!(s, "| stage / kernel | without | with | added |");
    let _ = writeln!(s, "|---|---:|---:|---:|");
    let (mut without, mut with) = (0.0, 0.0);
    for (name, a, b) in &c.kernels {
        let _ = writeln!(s, "| {name} | {a:.2} | {b:.2} | {:+.2} |", b - a);
        (without, with) = (without + a, with + b);
    }
    let _ = writeln!(s, "| sum | {without:.2} | {with:.2} | {:+.2} |", with - without);
}

fn forward_stages_section(s: &mut String, rows: &[Row]) {
    let _ = writeln!(s, "\n### Stage breakdown (GPU ms, median per stage)\n");
    let rows: Vec<(String, &[(&str, f64)])> = rows
        .iter()
        .map(|r| {
            let key = format!(
                "{} | {}x{} | {} | {}",
                density_name(r.density),
                r.width,
                r.height,
                r.gaussians,
                r.planes
            );
            (key, &r.stages[..])
        })
        .collect();
    stage_table(s, "room | image | Gaussians | planes", "---|---|---:|---:", &rows);
}

fn throughput_section(s: &mut String, t: &Throughput) {
    let _ = writeln!(s, "\n### Rasterize throughput (256x192, 100k Gaussians, no plane)\n");
    let _ = writeln!(
        s,
        "Evaluations: per pixel, the list entries `rasterize` visited before the pixel stopped. \
         The trivial loop (`shaders/bench/splat_loop.wgsl`) blends the same number of Gaussians in every \
         tile with one transmittance, no early exit and no sorting. Timed in turns over {} rounds \
         (a profiled frame, then one dispatch of each loop), so that the machine's drift hits all \
         alike: rates are medians over rounds, the percentages medians over rounds of the ratio.\n",
        t.rounds
    );
    let _ = writeln!(s, "| kernel | pixel-Gaussian evaluations/s | rasterize vs this |");
    let _ = writeln!(s, "|---|---:|---:|");
    let _ = writeln!(
        s,
        "| `rasterize` pass 1 ({} evaluations in {:.2} ms) | {:.3e} | |",
        t.evals, t.raster_ms, t.ours
    );
    let _ = writeln!(
        s,
        "| trivial splat loop, {} Gaussians per tile (the frame's mean list) | {:.3e} | {:.0}% |",
        t.mean_list,
        t.matched,
        100.0 * t.matched_ratio
    );
    let _ = writeln!(
        s,
        "| trivial splat loop, 2048 Gaussians per tile | {:.3e} | {:.0}% |",
        t.long,
        100.0 * t.long_ratio
    );
}

fn backward_section(s: &mut String, backward: &[BackwardRow]) {
    let _ = writeln!(s, "\n### Backward (256x192, 100k Gaussians)\n");
    let _ = writeln!(
        s,
        "One training-like step per row: `Renderer::render_into` with the depth-variance layer, then \
         `Renderer::backward` from upstream gradients on every layer (deterministic values in [-1, 1], \
         uploaded before the timer starts), which includes the readback of the plane gradients. \
         Wall ms: medians over {} steps; ratio: the median over steps of backward / forward. \
         The issue's bound is 2.5x.\n",
        backward[0].steps
    );
    let _ = writeln!(
        s,
        "| room | planes | forward ms | backward ms | forward + backward ms | backward / forward |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|");
    for b in backward {
        let _ = writeln!(
            s,
            "| {} | {} | {:.1} | {:.1} | {:.1} | {:.2}x |",
            density_name(b.density),
            b.planes,
            b.forward_ms,
            b.backward_ms,
            b.forward_ms + b.backward_ms,
            b.ratio
        );
    }
    let _ = writeln!(s, "\n#### Backward stage breakdown (GPU ms, median per stage)\n");
    let rows: Vec<(String, &[(&str, f64)])> = backward
        .iter()
        .map(|b| (format!("{} | {}", density_name(b.density), b.planes), &b.stages[..]))
        .collect();
    stage_table(s, "room | planes", "---|---:", &rows);
}

fn train_step_section(s: &mut String, steps: &[TrainStepRow]) {
    let _ = writeln!(s, "\n### Training step (256x192, {} Gaussians)\n", steps[0].gaussians);
    let _ = writeln!(
        s,
        "Whole `Trainer::train_step` calls on the capture-like room, joint stage (every loss of the \
         paper on, SH degree 3, no densification), target: the scene's own render darkened by 10%. \
         Step ms: median wall clock of a step taken alone (`train_step`, which waits for its \
         results); pipelined ms: wall clock per step of a loop that finishes each step after \
         recording the next (as `train` runs), over {0} steps. GPU ms: median over {0} profiled \
         steps of every pass's timestamp-query time summed; GPU busy: GPU ms over pipelined ms. \
         Phase ms: medians over {0} steps with the GPU idle at the end of each phase \
         (`Trainer::time_phases`). Stage table: medians of the timestamp-query time of each \
         stage, summed over the views of a step.\n",
        steps[0].steps
    );
    let names: Vec<&str> = steps[0].phases.iter().map(|p| p.0).collect();
    let _ = writeln!(
        s,
        "| planes | step ms | pipelined ms | GPU ms | GPU busy | {} |",
        names.join(" ms | ") + " ms"
    );
    let _ = writeln!(s, "|---:|---:|---:|---:|---:|{}", "---:|".repeat(names.len()));
    for t in steps {
        let cells: Vec<String> = t.phases.iter().map(|p| format!("{:.1}", p.1)).collect();
        let (step, pipelined) = (t.step_ms, t.pipelined_ms);
        let (gpu, busy) = (gpu_ms_cell(t.gpu_ms, 1), busy_percent(t.gpu_ms, pipelined));
        let _ = writeln!(
            s,
            "| {} | {step:.1} | {pipelined:.1} | {gpu} | {busy} | {} |",
            t.planes,
            cells.join(" | ")
        );
    }
    let _ = writeln!(s, "\n#### Training-step GPU stages (ms, median)\n");
    let rows: Vec<(String, &[(&str, f64)])> =
        steps.iter().map(|t| (t.planes.to_string(), &t.stages[..])).collect();
    stage_table(s, "planes", "---:", &rows);
}

/// GPU ms of a step, or "-" without timestamps.
pub fn gpu_ms_cell(gpu_ms: Option<f64>, decimals: usize) -> String {
    gpu_ms.map_or("-".to_string(), |ms| format!("{ms:.decimals$}"))
}

/// The share of a pipelined step's wall clock the GPU spent in passes, as "93%" ("-" without
/// timestamps).
pub fn busy_percent(gpu_ms: Option<f64>, wall_ms: f64) -> String {
    gpu_ms.map_or("-".to_string(), |ms| format!("{:.0}%", 100.0 * ms / wall_ms))
}

/// A table of GPU ms per stage: one row per (key cells, stages), one column per stage name in
/// order of first appearance, "-" where a row lacks the stage.
fn stage_table(
    s: &mut String,
    key_header: &str,
    key_align: &str,
    rows: &[(String, &[(&str, f64)])],
) {
    let mut names: Vec<&str> = Vec::new();
    for (_, stages) in rows {
        for (n, _) in stages.iter() {
            if !names.contains(n) {
                names.push(n);
            }
        }
    }
    let _ = writeln!(s, "| {key_header} | {} |", names.join(" | "));
    let _ = writeln!(s, "|{key_align}|{}", "---:|".repeat(names.len()));
    for (key, stages) in rows {
        let cells: Vec<String> = names
            .iter()
            .map(|n| {
                stages.iter().find(|x| x.0 == *n).map_or("-".into(), |x| format!("{:.2}", x.1))
            })
            .collect();
        let _ = writeln!(s, "| {key} | {} |", cells.join(" | "));
    }
}
