//! `train`: optimise Gaussians on a scene folder. With no `--data` it writes the built-in
//! synthetic glass scene and trains on it. Writes runs/<name>/: model.ply (INRIA layout),
//! planes.json, metrics.json, renders of the test views and their decomposition, a JSONL log,
//! and a checkpoint that `--resume` continues from.
use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use serde::{Deserialize, Serialize};
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use trgs_core::io::{write_atomic, write_planes_json, write_ply};
use trgs_core::rng::Rng;
use trgs_core::synthetic::{SyntheticConfig, generate, write_dataset};
use trgs_render::GpuContext;
use trgs_train::checkpoint::{CHECKPOINT_FILE, read_checkpoint, write_checkpoint};
use trgs_train::data::{self, Resolution, TrainingData};
use trgs_train::densify::ClassicSettings;
use trgs_train::eval::{
    Evaluation, Renderable, TruthComparison, compare_with_truth, evaluate, render_fps,
    write_renders,
};
use trgs_train::init::{SeedPoint, gaussians_from_points, random_points};
use trgs_train::mcmc::McmcSettings;
use trgs_train::plane_init::{PlaneInitSettings, initialise_planes};
use trgs_train::settings::TrainSettings;
use trgs_train::trainer::{StepTimes, Trainer};

const HELP: &str = "\
trgs train: TR-Gaussians training

USAGE:
    train [--data DIR] [--out DIR] [OPTIONS]
    train --out DIR --resume

OPTIONS:
    --data DIR          scene folder: COLMAP (sparse/0 + images/) or transforms.json, with
                        optional glass_masks/, planes.json and test_views.txt. Default: the
                        built-in synthetic scene, written to <out>/dataset
    --demo-scene KIND   the built-in scene: glass (default) or no-glass
    --out DIR           output folder (default: runs/demo)
    --iterations N      training steps (default 1000: about 20 minutes for the demo scene on a
                        2-core lavapipe; the paper uses 30000)
    --resolution W      train at width W (the height keeps the aspect ratio)
    --downscale F       train at 1/F of the image size
    --sh-degree D       largest SH degree, 0 to 3 (default 3)
    --eval-every N      evaluate the test views every N steps (default: 10 times a run)
    --checkpoint-every N  write <out>/checkpoint.trgs every N steps (default: at each evaluation)
    --resume            continue the run in --out from its checkpoint, with its own settings
    --random-init N     start from N random points when the scene has no sparse points
                        (default 10000)
    --no-planes         ignore the glass masks: plain 3DGS (the baseline of the comparisons)
    --densify MODE      classic (3DGS clone, split, prune, opacity reset; default), mcmc
                        (3DGS-MCMC: relocation of dead Gaussians, growth to --cap, noise,
                        opacity and scale regularisers) or none
    --cap N             mcmc: the most Gaussians (default 300000)
    --seed S            order of the training views (default 0)
    --profile           time every GPU stage of every step (timestamp queries) into log.jsonl

ABLATIONS (the paper's table; each switches one component off):
    --no-multi-stage    no stage 2: joint optimisation right after stage 1
    --no-depth-loss     no depth variance loss L_d
    --no-conflict-loss  no gradient conflict loss L_c
    --no-perturbation   no opacity perturbation
    --no-intensity      no reflection intensity map: C_r = C_raw
    --no-fresnel        no Schlick: a constant learnable R = R0
    -h, --help          this text
";

#[derive(Clone, Debug, Serialize, Deserialize)]
struct Args {
    data: Option<PathBuf>,
    demo_no_glass: bool,
    out: PathBuf,
    iterations: u32,
    resolution: Resolution,
    sh_degree: u32,
    eval_every: Option<u32>,
    checkpoint_every: Option<u32>,
    random_init: usize,
    densify: DensifyMode,
    /// MCMC's cap on the Gaussian count.
    cap: usize,
    no_planes: bool,
    seed: u64,
    profile: bool,
    ablations: Ablations,
}

/// How the Gaussian count changes during training.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
enum DensifyMode {
    Classic,
    Mcmc,
    None,
}

/// The paper's ablations: each true switches one component off.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
struct Ablations {
    no_multi_stage: bool,
    no_depth_loss: bool,
    no_conflict_loss: bool,
    no_perturbation: bool,
    no_intensity: bool,
    no_fresnel: bool,
}

impl Ablations {
    fn names(&self) -> Vec<&'static str> {
        [
            (self.no_multi_stage, "no multi-stage"),
            (self.no_depth_loss, "no L_d"),
            (self.no_conflict_loss, "no L_c"),
            (self.no_perturbation, "no opacity perturbation"),
            (self.no_intensity, "no reflection intensity"),
            (self.no_fresnel, "no Fresnel"),
        ]
        .into_iter()
        .filter_map(|(on, name)| on.then_some(name))
        .collect()
    }
}

/// What the command line asked for.
enum Command {
    Help,
    Train(Args),
    Resume { out: PathBuf },
}

fn parse_args() -> Result<Command> {
    let mut args = Args {
        data: None,
        demo_no_glass: false,
        out: PathBuf::from("runs/demo"),
        iterations: 1000,
        resolution: Resolution::Original,
        sh_degree: 3,
        eval_every: None,
        checkpoint_every: None,
        random_init: 10_000,
        densify: DensifyMode::Classic,
        cap: 300_000,
        no_planes: false,
        seed: 0,
        profile: false,
        ablations: Ablations::default(),
    };
    let mut resume = false;
    let mut others = Vec::new();
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        let mut value = |name: &str| it.next().with_context(|| format!("{name} needs a value"));
        fn num<T: std::str::FromStr>(name: &str, v: String) -> Result<T> {
            v.parse().map_err(|_| anyhow::anyhow!("{name} {v:?}: expected a number"))
        }
        if !matches!(a.as_str(), "--out" | "--resume") {
            others.push(a.clone());
        }
        let ab = &mut args.ablations;
        match a.as_str() {
            "-h" | "--help" => return Ok(Command::Help),
            "--data" => args.data = Some(PathBuf::from(value("--data")?)),
            "--demo-scene" => {
                args.demo_no_glass = match value("--demo-scene")?.as_str() {
                    "glass" => false,
                    "no-glass" => true,
                    other => bail!("--demo-scene {other:?}: expected glass or no-glass"),
                }
            }
            "--out" => args.out = PathBuf::from(value("--out")?),
            "--resume" => resume = true,
            "--iterations" => args.iterations = num("--iterations", value("--iterations")?)?,
            "--resolution" => {
                args.resolution = Resolution::Width(num("--resolution", value("--resolution")?)?)
            }
            "--downscale" => {
                args.resolution = Resolution::Downscale(num("--downscale", value("--downscale")?)?)
            }
            "--sh-degree" => args.sh_degree = num("--sh-degree", value("--sh-degree")?)?,
            "--eval-every" => args.eval_every = Some(num("--eval-every", value("--eval-every")?)?),
            "--checkpoint-every" => {
                args.checkpoint_every =
                    Some(num("--checkpoint-every", value("--checkpoint-every")?)?)
            }
            "--random-init" => args.random_init = num("--random-init", value("--random-init")?)?,
            "--densify" => {
                args.densify = match value("--densify")?.as_str() {
                    "classic" => DensifyMode::Classic,
                    "mcmc" => DensifyMode::Mcmc,
                    "none" => DensifyMode::None,
                    other => bail!("--densify {other:?}: expected classic, mcmc or none"),
                }
            }
            "--cap" => args.cap = num("--cap", value("--cap")?)?,
            "--no-planes" => args.no_planes = true,
            "--profile" => args.profile = true,
            "--seed" => args.seed = num("--seed", value("--seed")?)?,
            "--no-multi-stage" => ab.no_multi_stage = true,
            "--no-depth-loss" => ab.no_depth_loss = true,
            "--no-conflict-loss" => ab.no_conflict_loss = true,
            "--no-perturbation" => ab.no_perturbation = true,
            "--no-intensity" => ab.no_intensity = true,
            "--no-fresnel" => ab.no_fresnel = true,
            other => bail!("unknown argument {other:?}\n\n{HELP}"),
        }
    }
    if resume {
        if !others.is_empty() {
            bail!(
                "--resume continues a run with the settings it started with; drop {}",
                others.join(" ")
            );
        }
        return Ok(Command::Resume { out: args.out });
    }
    if args.iterations == 0 {
        bail!("--iterations must be at least 1");
    }
    if args.sh_degree > 3 {
        bail!("--sh-degree {}: expected 0 to 3", args.sh_degree);
    }
    if args.checkpoint_every == Some(0) || args.eval_every == Some(0) {
        bail!("--eval-every and --checkpoint-every must be at least 1");
    }
    Ok(Command::Train(args))
}

/// The training settings `args` ask for.
fn settings_of(args: &Args) -> TrainSettings {
    let mut s = TrainSettings::scaled(args.iterations);
    s.sh_degree = args.sh_degree;
    s.seed = args.seed;
    let ab = &args.ablations;
    if ab.no_multi_stage {
        s.stage2 = 0;
    }
    if ab.no_depth_loss {
        s.lambda_depth = 0.0;
    }
    if ab.no_conflict_loss {
        s.lambda_conflict = 0.0;
    }
    if ab.no_perturbation {
        s.perturb = None;
    }
    s.reflection.intensity = !ab.no_intensity;
    s.reflection.fresnel = !ab.no_fresnel;
    s
}

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
}

/// A line above the progress bar (`ProgressBar::println` prints nothing when the bar is hidden,
/// as it is when the output is not a terminal).
fn say(bar: &ProgressBar, line: String) {
    bar.suspend(|| println!("{line}"));
}

fn dataset_dir(args: &Args) -> Result<PathBuf> {
    if let Some(d) = &args.data {
        return Ok(d.clone());
    }
    let dir = args.out.join("dataset");
    if !dir.join("transforms.json").is_file() {
        let mut config = SyntheticConfig::default();
        if args.demo_no_glass {
            config.panes.clear();
        }
        write_dataset(&generate(&config), &dir)
            .with_context(|| format!("writing the demo scene to {}", dir.display()))?;
        let kind = if args.demo_no_glass { "scene without glass" } else { "glass scene" };
        println!("wrote the built-in synthetic {kind} to {}", dir.display());
    }
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
    let (args, resumed) = match parse_args()? {
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
            let mut state: RunState = serde_json::from_value(ck.extra.clone())
                .with_context(|| format!("{}: the run state is not readable", path.display()))?;
            state.args.out = out;
            println!(
                "resuming {} at step {} of {}",
                path.display(),
                ck.step,
                state.args.iterations
            );
            (state.args.clone(), Some((ck, state)))
        }
    };
    let data_dir = dataset_dir(&args)?;
    let data = load_data(&args, &data_dir)?;
    let ctx = GpuContext::new()?;
    let settings = settings_of(&args);
    let densify =
        (args.densify == DensifyMode::Classic).then(|| ClassicSettings::scaled(args.iterations));
    let mcmc = (args.densify == DensifyMode::Mcmc)
        .then(|| McmcSettings::scaled(args.iterations, args.cap));
    let log_path = args.out.join("log.jsonl");
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating the output folder {}", args.out.display()))?;
    let (mut trainer, mut state) = match resumed {
        Some((ck, state)) => {
            truncate_log(&log_path, ck.step)?;
            let mut trainer = Trainer::from_checkpoint(&ctx, &ck, settings, data.extent, densify)?;
            if let Some(m) = mcmc.clone() {
                trainer.enable_mcmc(m);
            }
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
            let gaussians = gaussians_from_points(&seeds, args.sh_degree);
            let mut trainer = Trainer::new(&ctx, &gaussians, &[], settings, data.extent)?;
            if let Some(d) = densify {
                trainer.enable_densification(d);
            }
            if let Some(m) = mcmc {
                trainer.enable_mcmc(m);
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
            };
            (trainer, state)
        }
    };
    trainer.profile = args.profile;
    let cameras: Vec<_> = data.train.iter().map(|v| v.camera.clone()).collect();
    trainer.set_training_cameras(&cameras);
    let mut log = std::fs::OpenOptions::new()
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
            init_planes(&mut trainer, &data, &mut rng, &bar)?;
        }
        let ts = Instant::now();
        let stats = trainer.train_step(&data.train[vi])?;
        state.train_seconds += ts.elapsed().as_secs_f64();
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
        if trainer.step % eval_every == 0 || trainer.step == args.iterations {
            let e = evaluate(&model_of(&trainer), &data, trainer.step, state.train_seconds)?;
            say(
                &bar,
                format!(
                    "step {}: test PSNR {:.2} dB, SSIM {:.4} ({:.0} s of training)",
                    e.step, e.psnr, e.ssim, e.seconds
                ),
            );
            writeln!(log, "{}", serde_json::json!({"eval": &e}))?;
            state.evaluations.push(e);
        }
        if trainer.step % checkpoint_every == 0 && trainer.step < args.iterations {
            state.rng_state = rng.state();
            state.seconds = t0.elapsed().as_secs_f64();
            let extra = serde_json::to_value(&state)?;
            let path = args.out.join(CHECKPOINT_FILE);
            write_checkpoint(&path, &trainer.checkpoint(extra))?;
            log.flush()?;
        }
    }
    bar.finish();
    finish(&args, &trainer, &data, &data_dir, &state)
}

/// Initialise the planes from the glass masks (the end of stage 1).
fn init_planes(
    trainer: &mut Trainer,
    data: &TrainingData,
    rng: &mut Rng,
    bar: &ProgressBar,
) -> Result<()> {
    let init = initialise_planes(
        &trainer.gaussians(),
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
    let gaussians = trainer.gaussians();
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
