//! `train`: optimise Gaussians on a scene folder. With no `--data` it writes a built-in
//! synthetic scene (the showcase unless `--demo-scene` names another) and trains on it. Writes
//! runs/<name>/: model.ply (INRIA layout), planes.json, metrics.json, renders of the test views
//! and their decomposition, a JSONL log, and a checkpoint that `--resume` continues from.
use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use serde::{Deserialize, Serialize};
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use trgs_core::io::{
    remove_stale_temporaries, write_atomic, write_cameras_json, write_planes_json, write_ply,
};
use trgs_core::rng::Rng;
use trgs_core::synthetic::{generate, write_dataset};
use trgs_render::GpuContext;
use trgs_train::checkpoint::{CHECKPOINT_FILE, read_checkpoint, write_checkpoint};
use trgs_train::data::{self, TrainingData};
use trgs_train::densify::{ClassicSettings, Densification, McmcSettings};
use trgs_train::eval::{
    Evaluation, Renderable, TruthComparison, compare_with_truth, evaluate, render_fps,
    write_renders,
};
use trgs_train::init::{SeedPoint, gaussians_from_points, random_points};
use trgs_train::plane_init::{PlaneInitSettings, initialise_planes};
use trgs_train::trainer::{StepTimes, Trainer};
use trgs_viewer::{LiveFeed, Snapshot, Source, ViewerOptions};

/// The shortest time between two snapshots for the viewer (each is a readback of the scene).
const SNAPSHOT_INTERVAL: Duration = Duration::from_millis(500);

#[path = "train/args.rs"]
mod args;

use args::{Args, Command, DemoScene, DensifyMode, HELP, parse_args, settings_of};

/// The `train` bin's own state in a checkpoint, besides the trainer's.
#[derive(Serialize, Deserialize)]
struct RunState {
    args: Args,
    rng_state: u64,
    /// Training views still to visit in this epoch (popped from the back).
    order: Vec<usize>,
    evaluations: Vec<Evaluation>,
    train_seconds: f64,
    /// Wall-clock seconds of the run so far (training, evaluation and checkpoints).
    seconds: f64,
    /// Summed milliseconds of each step phase.
    phase_ms: StepTimes,
    /// The training views' names, in the order `order` indexes them: a resumed run refuses a
    /// dataset whose views changed (empty in checkpoints that predate it).
    #[serde(default)]
    train_views: Vec<String>,
}

/// A line above the progress bar (`ProgressBar::println` prints nothing when the bar is hidden,
/// as it is when the output is not a terminal).
fn say(bar: &ProgressBar, line: String) {
    bar.suspend(|| println!("{line}"));
}

/// The file that a complete demo dataset ends with: it names the built-in scene the folder holds
/// (its `--demo-scene` value). It is written last, so a folder without it (a write cut short) is
/// written again; a run that asks for another scene in the same `--out` is refused instead of
/// training on a folder that mixes the two.
const DEMO_SCENE_MARKER: &str = "demo_scene.txt";

fn dataset_dir(args: &Args) -> Result<PathBuf> {
    if let Some(d) = &args.data {
        return Ok(d.clone());
    }
    let scene = args.demo_scene;
    let dir = args.out.join("dataset");
    let marker = dir.join(DEMO_SCENE_MARKER);
    if let Ok(found) = std::fs::read_to_string(&marker) {
        let held = DemoScene::parse(found.trim()).with_context(|| {
            format!("{}: {:?} is not a built-in scene's name", marker.display(), found.trim())
        })?;
        if held != scene {
            bail!(
                "{} holds the built-in scene `--demo-scene {}`, not `{}`: choose another --out, \
                 or remove that folder",
                dir.display(),
                held.name(),
                scene.name()
            );
        }
        return Ok(dir);
    }
    write_dataset(&generate(&scene.config()), &dir)
        .with_context(|| format!("writing the demo scene to {}", dir.display()))?;
    write_atomic(&marker, format!("{}\n", scene.name()).as_bytes())?;
    println!("wrote the built-in synthetic {} to {}", scene.description(), dir.display());
    Ok(dir)
}

fn load_data(args: &Args, data_dir: &Path) -> Result<TrainingData> {
    let mut data = data::load(data_dir, args.resolution)?;
    if args.no_planes {
        data.materials.clear();
    }
    let (w, h) = data.size();
    println!(
        "dataset {}: {} training and {} test views at {w}x{h}, {} sparse points, extent {:.2}",
        data_dir.display(),
        data.train.len(),
        data.test.len(),
        data.points.len(),
        data.extent
    );
    if args.no_planes {
        println!("--no-planes: training plain 3DGS");
    } else if data.materials.is_empty() {
        println!("no glass masks: no reflection planes, training plain 3DGS");
    } else {
        println!(
            "glass masks with labels {:?}: planes are initialised after stage 1",
            data.materials
        );
    }
    let ablations = args.ablations.names();
    if !ablations.is_empty() {
        println!("ablations: {}", ablations.join(", "));
    }
    Ok(data)
}

/// Keep the lines of `log` up to step `step` (a resumed run rewrites what came after).
fn truncate_log(log: &Path, step: u32) -> Result<()> {
    let Ok(text) = std::fs::read_to_string(log) else { return Ok(()) };
    let keep: Vec<&str> = text
        .lines()
        .filter(|line| {
            let v: serde_json::Value = serde_json::from_str(line).unwrap_or_default();
            let s = v.get("step").or_else(|| v.get("eval").and_then(|e| e.get("step")));
            s.and_then(serde_json::Value::as_u64).is_some_and(|s| s <= u64::from(step))
        })
        .collect();
    let mut out = keep.join("\n");
    if !out.is_empty() {
        out.push('\n');
    }
    write_atomic(log, out.as_bytes())?;
    Ok(())
}

fn main() -> Result<()> {
    let (command, viewer) = parse_args()?;
    let (args, resumed) = match command {
        Command::Help => {
            print!("{HELP}");
            return Ok(());
        }
        Command::Train(args) => (args, None),
        Command::Resume { out } => {
            let path = out.join(CHECKPOINT_FILE);
            let ck = read_checkpoint(&path).with_context(|| {
                format!("--resume: no checkpoint to continue from in {}", out.display())
            })?;
            let mut extra = ck.extra.clone();
            if let Some(record) = extra.get_mut("args") {
                args::upgrade_args_record(record);
            }
            let mut state: RunState = serde_json::from_value(extra)
                .with_context(|| format!("{}: the run state is not readable", path.display()))?;
            state.args.out = out;
            if ck.step >= state.args.iterations {
                println!(
                    "{}: the run finished at step {}; writing its results again",
                    path.display(),
                    ck.step
                );
            } else {
                println!(
                    "resuming {} at step {} of {}",
                    path.display(),
                    ck.step,
                    state.args.iterations
                );
            }
            (state.args.clone(), Some((ck, state)))
        }
    };
    if !viewer {
        return train(args, resumed, None);
    }
    // The window needs the main thread; training runs beside it and publishes snapshots.
    let feed = LiveFeed::new();
    let worker_feed = feed.clone();
    let worker = std::thread::Builder::new()
        .name("train".into())
        .spawn(move || {
            let result = train(args, resumed, Some(&worker_feed));
            if let Err(e) = &result {
                // Said at once: the window stays open until the user closes it.
                eprintln!("error: {e:#}");
                worker_feed.set_status(format!("training failed: {e:#}"));
            }
            result
        })
        .context("starting the training thread")?;
    let options = ViewerOptions { source: Source::Live(feed.clone()), ..Default::default() };
    if let Err(e) = trgs_viewer::run(options) {
        eprintln!("{e:#}; training goes on without the viewer");
    }
    feed.close();
    worker.join().map_err(|_| anyhow::anyhow!("the training thread panicked"))?
}

/// A run from its start or from a checkpoint, publishing to `feed` when a viewer watches.
fn train(
    args: Args,
    resumed: Option<(trgs_train::checkpoint::Checkpoint, RunState)>,
    feed: Option<&LiveFeed>,
) -> Result<()> {
    let data_dir = dataset_dir(&args)?;
    let data = load_data(&args, &data_dir)?;
    let ctx = GpuContext::new()?;
    let settings = settings_of(&args);
    let densification = match args.densify {
        DensifyMode::Classic => Densification::Classic(ClassicSettings::scaled(args.iterations)),
        DensifyMode::Mcmc => Densification::Mcmc(McmcSettings::scaled(args.iterations, args.cap)),
        DensifyMode::None => Densification::None,
    };
    let log_path = args.out.join("log.jsonl");
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating the output folder {}", args.out.display()))?;
    let was_finished = resumed.as_ref().is_some_and(|(ck, _)| ck.step >= args.iterations);
    // A checkpoint's temporary file is as large as the checkpoint.
    let outputs = [CHECKPOINT_FILE, "log.jsonl", "metrics.json", "model.ply", "planes.json"];
    remove_stale_temporaries(&args.out, &outputs);
    let (mut trainer, mut state) = match resumed {
        Some((ck, mut state)) => {
            check_same_views(&state, &data, &data_dir)?;
            // A checkpoint from before the names were kept: they are known good now.
            if state.train_views.is_empty() {
                state.train_views = data.train.iter().map(|v| v.camera.name.clone()).collect();
            }
            truncate_log(&log_path, ck.step)?;
            let trainer =
                Trainer::from_checkpoint(&ctx, &ck, settings, data.extent, &densification)?;
            (trainer, state)
        }
        None => {
            let mut rng = Rng::new(args.seed);
            let seeds: Vec<SeedPoint> = if data.points.is_empty() {
                let r = data.extent;
                println!(
                    "no sparse points: {} random points within {r:.2} of the cameras' centre",
                    args.random_init
                );
                random_points(args.random_init, data.centre - r, data.centre + r, &mut rng)
            } else {
                data.points.iter().map(|&(position, color)| SeedPoint { position, color }).collect()
            };
            let shape = densification.initial_shape();
            let gaussians = gaussians_from_points(&seeds, args.sh_degree, shape);
            let mut trainer = Trainer::new(&ctx, &gaussians, &[], settings, data.extent)?;
            trainer.set_densification(&densification);
            // A previous run's checkpoint in this folder would be what `--resume` continues if
            // this run stopped before its own first one.
            let old = args.out.join(CHECKPOINT_FILE);
            if old.is_file() {
                std::fs::remove_file(&old)
                    .with_context(|| format!("removing the previous run's {}", old.display()))?;
                println!(
                    "a new run in {}: removed the previous run's checkpoint",
                    args.out.display()
                );
            }
            std::fs::File::create(&log_path)
                .with_context(|| format!("creating {}", log_path.display()))?;
            let state = RunState {
                args: args.clone(),
                rng_state: rng.state(),
                order: Vec::new(),
                evaluations: Vec::new(),
                train_seconds: 0.0,
                seconds: 0.0,
                phase_ms: StepTimes::default(),
                train_views: data.train.iter().map(|v| v.camera.name.clone()).collect(),
            };
            (trainer, state)
        }
    };
    trainer.profile = args.profile;
    let cameras: Vec<_> = data.train.iter().map(|v| v.camera.clone()).collect();
    trainer.set_training_cameras(&cameras);
    // Every view once, as the INRIA code writes it: viewers snap to these. (Not eval_views():
    // without a test split it is the first training views, which are listed already.)
    let views: Vec<_> =
        cameras.iter().cloned().chain(data.test.iter().map(|v| v.camera.clone())).collect();
    write_cameras_json(&args.out.join("cameras.json"), &views)?;
    if let Some(feed) = feed {
        feed.set_cameras(views);
    }
    let mut log = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&log_path)
        .with_context(|| format!("opening {}", log_path.display()))?;
    let mut rng = Rng::from_state(state.rng_state);

    let eval_every = args.eval_every.unwrap_or((args.iterations / 10).max(1));
    let checkpoint_every = args.checkpoint_every.unwrap_or(eval_every);
    let bar = ProgressBar::new(u64::from(args.iterations));
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} steps  {per_sec}  eta {eta}  {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_position(u64::from(trainer.step));
    bar.reset_eta();
    let t0 = Instant::now()
        .checked_sub(Duration::from_secs_f64(state.seconds))
        .unwrap_or_else(Instant::now);
    while trainer.step < args.iterations {
        if state.order.is_empty() {
            state.order = (0..data.train.len()).collect();
            for i in (1..state.order.len()).rev() {
                state.order.swap(i, rng.below(i + 1));
            }
        }
        let Some(vi) = state.order.pop() else { break };
        if trainer.step == trainer.settings.stage1
            && !data.materials.is_empty()
            && trainer.planes().is_empty()
        {
            // Part of training: it counts in the time that PSNR is reported against.
            let ti = Instant::now();
            init_planes(&mut trainer, &data, &mut rng, &bar)?;
            state.train_seconds += ti.elapsed().as_secs_f64();
        }
        let ts = Instant::now();
        let next = trainer.step + 1;
        let eval_now = next % eval_every == 0 || next == args.iterations;
        let (mut evaluation, mut eval_time) = (None, Duration::ZERO);
        let before = state.train_seconds;
        let stats = trainer.train_step_then(&data.train[vi], |t| {
            // Before the step's densification, reset or perturbation (see train_step_then).
            if eval_now {
                let te = Instant::now();
                let seconds = before + ts.elapsed().as_secs_f64();
                evaluation = Some(evaluate(&model_of(t), &data, t.step, seconds)?);
                eval_time = te.elapsed();
            }
            Ok(())
        });
        // A failed step (a lost GPU, no memory left) loses nothing saved: say where to go on.
        let stats = stats.with_context(|| {
            format!(
                "training stopped at step {next}; `train --out {} --resume` continues from the \
                 last checkpoint",
                args.out.display()
            )
        })?;
        state.train_seconds += ts.elapsed().saturating_sub(eval_time).as_secs_f64();
        state.phase_ms.accumulate(&stats.times);
        let phases: serde_json::Map<_, _> = stats
            .times
            .phases()
            .iter()
            .map(|(k, v)| (k.to_string(), serde_json::json!(v)))
            .collect();
        let gpu: Vec<_> = stats.gpu_stages.iter().map(|(k, v)| serde_json::json!([k, v])).collect();
        writeln!(
            log,
            "{}",
            serde_json::json!({"step": trainer.step, "view": data.train[vi].camera.name,
                "loss": stats.loss, "psnr": stats.psnr, "gaussians": trainer.scene().len(),
                "seconds": t0.elapsed().as_secs_f64(), "ms": phases, "gpu_ms": gpu,
                "perturbed": stats.perturbed})
        )?;
        bar.set_position(u64::from(trainer.step));
        bar.set_message(format!(
            "loss {:.4}  psnr {:.2}  {} Gaussians",
            stats.loss,
            stats.psnr,
            trainer.scene().len()
        ));
        if let Some(feed) = feed
            && feed.wants_snapshot(SNAPSHOT_INTERVAL)
        {
            feed.publish(Snapshot {
                gaussians: trainer.gaussians()?,
                planes: trainer.planes().to_vec(),
                reflection: trainer.render_options().reflection,
                status: format!(
                    "training: step {} of {}, loss {:.4}, PSNR {:.2} dB, {} Gaussians",
                    trainer.step,
                    args.iterations,
                    stats.loss,
                    stats.psnr,
                    trainer.scene().len()
                ),
            });
        }
        if let Some(e) = evaluation {
            say(
                &bar,
                format!(
                    "step {}: PSNR {:.2} dB, SSIM {:.4} on the {} views ({:.0} s of training)",
                    e.step,
                    e.psnr,
                    e.ssim,
                    data.eval_views_name(),
                    e.seconds
                ),
            );
            writeln!(log, "{}", serde_json::json!({"eval": &e}))?;
            state.evaluations.push(e);
        }
        if trainer.step % checkpoint_every == 0 && trainer.step < args.iterations {
            save_checkpoint(&args.out, &trainer, &mut state, &rng, t0)?;
            log.flush()?;
        }
    }
    bar.finish();
    // The finished state, so that `--resume` after the end writes the same results again
    // instead of training on from the last intermediate checkpoint.
    if !was_finished {
        save_checkpoint(&args.out, &trainer, &mut state, &rng, t0)?;
    }
    finish(&args, &trainer, &data, &data_dir, &state)?;
    if let Some(feed) = feed {
        // The final model, whatever the snapshot interval left the viewer with.
        feed.publish(Snapshot {
            gaussians: trainer.gaussians()?,
            planes: trainer.planes().to_vec(),
            reflection: trainer.render_options().reflection,
            status: format!("training finished: results in {}", args.out.display()),
        });
    }
    Ok(())
}

/// Write `out`'s checkpoint: the trainer's state and the run's own (random state, wall clock).
fn save_checkpoint(
    out: &Path,
    trainer: &Trainer,
    state: &mut RunState,
    rng: &Rng,
    t0: Instant,
) -> Result<()> {
    state.rng_state = rng.state();
    state.seconds = t0.elapsed().as_secs_f64();
    let extra = serde_json::to_value(&*state)?;
    write_checkpoint(&out.join(CHECKPOINT_FILE), &trainer.checkpoint(extra)?)?;
    Ok(())
}

/// Refuse to resume on a dataset whose training views are not those the run started with
/// (`state.order` indexes them).
fn check_same_views(state: &RunState, data: &TrainingData, data_dir: &Path) -> Result<()> {
    let now: Vec<&str> = data.train.iter().map(|v| v.camera.name.as_str()).collect();
    let changed = if state.train_views.is_empty() {
        state.order.iter().any(|&i| i >= now.len())
    } else {
        state.train_views.iter().map(String::as_str).ne(now.iter().copied())
    };
    if changed {
        bail!(
            "--resume: the training views of {} are not those the run started with ({} then, {} \
             now): restore the dataset, or start a new run",
            data_dir.display(),
            if state.train_views.is_empty() {
                "unknown".into()
            } else {
                state.train_views.len().to_string()
            },
            now.len()
        );
    }
    Ok(())
}

/// Initialise the planes from the glass masks (the end of stage 1).
fn init_planes(
    trainer: &mut Trainer,
    data: &TrainingData,
    rng: &mut Rng,
    bar: &ProgressBar,
) -> Result<()> {
    let init = initialise_planes(
        &trainer.gaussians()?,
        &data.train,
        &data.materials,
        data.extent,
        &PlaneInitSettings::default(),
        rng,
    );
    for (label, why) in &init.failed {
        say(bar, format!("plane {label}: not initialised: {why}"));
    }
    for (label, p) in init.labels.iter().zip(&init.planes) {
        let n = p.unit_normal();
        say(
            bar,
            format!(
                "plane {label}: centre ({:.3}, {:.3}, {:.3}), normal ({:.3}, {:.3}, {:.3}), {:.2} x {:.2}",
                p.centre.x, p.centre.y, p.centre.z, n.x, n.y, n.z, p.width, p.height
            ),
        );
    }
    trainer.add_planes(&init.planes, &init.glass)
}

fn model_of(trainer: &Trainer) -> Renderable<'_> {
    Renderable {
        ctx: trainer.context(),
        renderer: trainer.renderer(),
        scene: trainer.scene(),
        options: trainer.render_options(),
    }
}

/// Final evaluation and outputs.
fn finish(
    args: &Args,
    trainer: &Trainer,
    data: &TrainingData,
    data_dir: &Path,
    state: &RunState,
) -> Result<()> {
    let last = state.evaluations.last().cloned().context("no evaluation was made")?;
    let model = model_of(trainer);
    let truth = compare_with_truth(&model, trainer.planes(), data, data_dir)?;
    if let Some(t) = &truth {
        println!("against the ground truth in {}: {t}", data_dir.join("gt").display());
    }
    let steps = f64::from(trainer.step.max(1));
    let mean_ms: Vec<(&str, f64)> =
        state.phase_ms.phases().iter().map(|&(k, v)| (k, v / steps)).collect();
    println!(
        "ms per step: {}",
        mean_ms.iter().map(|(k, v)| format!("{k} {v:.1}")).collect::<Vec<_>>().join(", ")
    );
    let out = &args.out;
    let gaussians = trainer.gaussians()?;
    // A model other tools cannot read (a NaN, a zero quaternion) is not written as one.
    trgs_core::scene::validate_gaussians(&gaussians)
        .context("the trained model is not valid, so model.ply was not written")?;
    write_ply(&out.join("model.ply"), &gaussians)?;
    write_planes_json(&out.join("planes.json"), trainer.planes())?;
    write_renders(&model, data, &out.join("renders"))?;
    let fps = render_fps(&model, data)?;
    let metrics = metrics_json(args, trainer, data, &last, state, &mean_ms, fps, truth.as_ref());
    write_atomic(&out.join("metrics.json"), serde_json::to_string_pretty(&metrics)?.as_bytes())?;
    println!(
        "done: {} steps in {:.0} s ({:.0} ms per step), test PSNR {:.2} dB, SSIM {:.4}; results in {}",
        trainer.step,
        state.train_seconds,
        1e3 * state.train_seconds / steps,
        last.psnr,
        last.ssim,
        out.display()
    );
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn metrics_json(
    args: &Args,
    trainer: &Trainer,
    data: &TrainingData,
    last: &Evaluation,
    state: &RunState,
    step_ms: &[(&str, f64)],
    fps: f64,
    truth: Option<&TruthComparison>,
) -> serde_json::Value {
    serde_json::json!({
        "psnr": last.psnr,
        "ssim": last.ssim,
        "eval_views": data.eval_views_name(),
        "views": last.views.iter().map(|(n, p, s)| serde_json::json!({"name": n, "psnr": p, "ssim": s})).collect::<Vec<_>>(),
        "train_seconds": state.train_seconds,
        "step_ms": step_ms.iter().map(|(k, v)| (k.to_string(), serde_json::json!(v))).collect::<serde_json::Map<_, _>>(),
        "steps": trainer.step,
        "gaussians": trainer.scene().len(),
        "planes": trainer.planes().len(),
        "render_fps": fps,
        "resolution": [data.size().0, data.size().1],
        "ablations": args.ablations.names(),
        "reflection_model": {"fresnel": !args.ablations.no_fresnel, "intensity": !args.ablations.no_intensity},
        "data": args.data,
        "no_planes": args.no_planes,
        "truth": truth,
        "psnr_over_time": state.evaluations.iter().map(|e| serde_json::json!({"step": e.step, "seconds": e.seconds, "psnr": e.psnr, "ssim": e.ssim})).collect::<Vec<_>>(),
    })
}
