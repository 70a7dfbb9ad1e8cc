//! `train`: optimise Gaussians on a scene folder. With no `--data` it writes the built-in
//! synthetic glass scene and trains on it. Writes runs/<name>/: model.ply (INRIA layout),
//! planes.json, metrics.json, renders of the test views, and a JSONL log.
use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;
use trgs_core::io::{write_atomic, write_planes_json, write_ply, write_png_rgb};
use trgs_core::metrics::{psnr, ssim};
use trgs_core::rng::Rng;
use trgs_core::synthetic::{SyntheticConfig, generate, write_dataset};
use trgs_render::{GpuContext, Layer};
use trgs_train::data::{self, Resolution, TrainingData};
use trgs_train::densify::ClassicSettings;
use trgs_train::init::{SeedPoint, gaussians_from_points, random_points};
use trgs_train::plane_init::{PlaneInitSettings, initialise_planes};
use trgs_train::settings::TrainSettings;
use trgs_train::trainer::{StepTimes, Trainer};

const HELP: &str = "\
trgs train: TR-Gaussians training

USAGE:
    train [--data DIR] [--out DIR] [OPTIONS]

OPTIONS:
    --data DIR          scene folder: COLMAP (sparse/0 + images/) or transforms.json, with
                        optional glass_masks/, planes.json and test_views.txt. Default: the
                        built-in synthetic glass scene, written to <out>/dataset
    --out DIR           output folder (default: runs/demo)
    --iterations N      training steps (default 1000: about 20 minutes for the demo scene on a 2-core lavapipe; the paper
                        uses 30000)
    --resolution W      train at width W (the height keeps the aspect ratio)
    --downscale F       train at 1/F of the image size
    --sh-degree D       largest SH degree, 0 to 3 (default 3)
    --eval-every N      evaluate the test views every N steps (default: 10 times a run)
    --random-init N     start from N random points when the scene has no sparse points
                        (default 10000)
    --no-planes         ignore the glass masks: plain 3DGS (the baseline of the comparisons)
    --densify MODE      classic (3DGS clone, split, prune, opacity reset; default) or none
    --seed S            order of the training views (default 0)
    --profile           time every GPU stage of every step (timestamp queries) into log.jsonl
    -h, --help          this text
";

struct Args {
    data: Option<PathBuf>,
    out: PathBuf,
    iterations: u32,
    resolution: Resolution,
    sh_degree: u32,
    eval_every: Option<u32>,
    random_init: usize,
    densify: bool,
    no_planes: bool,
    seed: u64,
    profile: bool,
}

fn parse_args() -> Result<Option<Args>> {
    let mut args = Args {
        data: None,
        out: PathBuf::from("runs/demo"),
        iterations: 1000,
        resolution: Resolution::Original,
        sh_degree: 3,
        eval_every: None,
        random_init: 10_000,
        densify: true,
        no_planes: false,
        seed: 0,
        profile: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        let mut value = |name: &str| it.next().with_context(|| format!("{name} needs a value"));
        fn num<T: std::str::FromStr>(name: &str, v: String) -> Result<T> {
            v.parse().map_err(|_| anyhow::anyhow!("{name} {v:?}: expected a number"))
        }
        match a.as_str() {
            "-h" | "--help" => return Ok(None),
            "--data" => args.data = Some(PathBuf::from(value("--data")?)),
            "--out" => args.out = PathBuf::from(value("--out")?),
            "--iterations" => args.iterations = num("--iterations", value("--iterations")?)?,
            "--resolution" => {
                args.resolution = Resolution::Width(num("--resolution", value("--resolution")?)?)
            }
            "--downscale" => {
                args.resolution = Resolution::Downscale(num("--downscale", value("--downscale")?)?)
            }
            "--sh-degree" => args.sh_degree = num("--sh-degree", value("--sh-degree")?)?,
            "--eval-every" => args.eval_every = Some(num("--eval-every", value("--eval-every")?)?),
            "--random-init" => args.random_init = num("--random-init", value("--random-init")?)?,
            "--densify" => {
                args.densify = match value("--densify")?.as_str() {
                    "classic" => true,
                    "none" => false,
                    other => bail!("--densify {other:?}: expected classic or none"),
                }
            }
            "--no-planes" => args.no_planes = true,
            "--profile" => args.profile = true,
            "--seed" => args.seed = num("--seed", value("--seed")?)?,
            other => bail!("unknown argument {other:?}\n\n{HELP}"),
        }
    }
    if args.iterations == 0 {
        bail!("--iterations must be at least 1");
    }
    if args.sh_degree > 3 {
        bail!("--sh-degree {}: expected 0 to 3", args.sh_degree);
    }
    Ok(Some(args))
}

/// PSNR and SSIM of every test view (or of the first training views when there is no test
/// split), and their means.
#[derive(Clone, Debug, serde::Serialize)]
struct Evaluation {
    step: u32,
    seconds: f64,
    views: Vec<(String, f64, f64)>,
    psnr: f64,
    ssim: f64,
}

fn evaluate(trainer: &Trainer, data: &TrainingData, t0: Instant) -> Result<Evaluation> {
    let views = data.eval_views();
    let mut rows = Vec::new();
    for v in views {
        let frame = trainer.render(&v.camera)?;
        let color = frame.read_layer(trainer.context(), Layer::Color);
        rows.push((v.camera.name.clone(), psnr(&color, &v.image)?, ssim(&color, &v.image)?));
    }
    let n = rows.len().max(1) as f64;
    Ok(Evaluation {
        step: trainer.step,
        seconds: t0.elapsed().as_secs_f64(),
        psnr: rows.iter().map(|r| r.1).sum::<f64>() / n,
        ssim: rows.iter().map(|r| r.2).sum::<f64>() / n,
        views: rows,
    })
}

/// A line above the progress bar (`ProgressBar::println` prints nothing when the bar is hidden,
/// as it is when the output is not a terminal).
fn say(bar: &ProgressBar, line: String) {
    bar.suspend(|| println!("{line}"));
}

fn main() -> Result<()> {
    let Some(args) = parse_args()? else {
        print!("{HELP}");
        return Ok(());
    };
    let data_dir = match &args.data {
        Some(d) => d.clone(),
        None => {
            let dir = args.out.join("dataset");
            if !dir.join("transforms.json").is_file() {
                let scene = generate(&SyntheticConfig::default());
                write_dataset(&scene, &dir)
                    .with_context(|| format!("writing the demo scene to {}", dir.display()))?;
                println!("wrote the built-in synthetic glass scene to {}", dir.display());
            }
            dir
        }
    };
    let mut data = data::load(&data_dir, args.resolution)?;
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
    let mut settings = TrainSettings::scaled(args.iterations);
    settings.sh_degree = args.sh_degree;
    settings.seed = args.seed;
    let ctx = GpuContext::new()?;
    let mut trainer = Trainer::new(&ctx, &gaussians, &[], settings, data.extent)?;
    trainer.profile = args.profile;
    if args.densify {
        trainer.enable_densification(ClassicSettings::scaled(args.iterations));
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating the output folder {}", args.out.display()))?;
    let log_path = args.out.join("log.jsonl");
    let mut log = std::fs::File::create(&log_path)
        .with_context(|| format!("creating {}", log_path.display()))?;

    let eval_every = args.eval_every.unwrap_or((args.iterations / 10).max(1));
    let bar = ProgressBar::new(u64::from(args.iterations));
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} steps  {per_sec}  eta {eta}  {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let t0 = Instant::now();
    let mut evaluations = Vec::new();
    let mut order: Vec<usize> = Vec::new();
    let mut train_seconds = 0.0;
    let mut phase_ms = StepTimes::default();
    while trainer.step < args.iterations {
        if order.is_empty() {
            order = (0..data.train.len()).collect();
            for i in (1..order.len()).rev() {
                order.swap(i, rng.below(i + 1));
            }
        }
        let Some(vi) = order.pop() else { break };
        if trainer.step == trainer.settings.stage1
            && !data.materials.is_empty()
            && trainer.planes().is_empty()
        {
            let init = initialise_planes(
                &trainer.gaussians(),
                &data.train,
                &data.materials,
                data.extent,
                &PlaneInitSettings::default(),
                &mut rng,
            );
            for (label, why) in &init.failed {
                say(&bar, format!("plane {label}: not initialised: {why}"));
            }
            for (label, p) in init.labels.iter().zip(&init.planes) {
                let n = p.unit_normal();
                say(
                    &bar,
                    format!(
                        "plane {label}: centre ({:.3}, {:.3}, {:.3}), normal ({:.3}, {:.3}, {:.3}), {:.2} x {:.2}",
                        p.centre.x, p.centre.y, p.centre.z, n.x, n.y, n.z, p.width, p.height
                    ),
                );
            }
            trainer.add_planes(&init.planes, &init.glass)?;
        }
        let ts = Instant::now();
        let stats = trainer.train_step(&data.train[vi])?;
        train_seconds += ts.elapsed().as_secs_f64();
        phase_ms.accumulate(&stats.times);
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
                "seconds": t0.elapsed().as_secs_f64(), "ms": phases, "gpu_ms": gpu})
        )?;
        bar.set_position(u64::from(trainer.step));
        bar.set_message(format!(
            "loss {:.4}  psnr {:.2}  {} Gaussians",
            stats.loss,
            stats.psnr,
            trainer.scene().len()
        ));
        if trainer.step % eval_every == 0 || trainer.step == args.iterations {
            let e = evaluate(&trainer, &data, t0)?;
            say(
                &bar,
                format!(
                    "step {}: test PSNR {:.2} dB, SSIM {:.4} ({:.0} s)",
                    e.step, e.psnr, e.ssim, e.seconds
                ),
            );
            writeln!(log, "{}", serde_json::json!({"eval": &e}))?;
            evaluations.push(e);
        }
    }
    bar.finish();
    let last = evaluations.last().cloned().context("no evaluation was made")?;
    let truth = compare_with_truth(&trainer, &data, &data_dir)?;
    if let Some(t) = &truth {
        println!("against the ground truth in {}: {t}", data_dir.join("gt").display());
    }
    let steps = f64::from(trainer.step.max(1));
    let mean_ms: Vec<(&str, f64)> =
        phase_ms.phases().iter().map(|&(k, v)| (k, v / steps)).collect();
    println!(
        "ms per step: {}",
        mean_ms.iter().map(|(k, v)| format!("{k} {v:.1}")).collect::<Vec<_>>().join(", ")
    );
    let run = RunSummary { train_seconds, step_ms: mean_ms, truth: truth.as_ref() };
    write_outputs(&args.out, &trainer, &data, &last, &evaluations, &run)?;
    println!(
        "done: {} steps in {:.0} s ({:.0} ms per step), test PSNR {:.2} dB, SSIM {:.4}; results in {}",
        trainer.step,
        train_seconds,
        1e3 * train_seconds / f64::from(trainer.step.max(1)),
        last.psnr,
        last.ssim,
        args.out.display()
    );
    Ok(())
}

/// What a synthetic scene's ground truth (`gt/planes.json`, `gt/transmission/`) says of the run.
#[derive(Clone, Debug, serde::Serialize)]
struct TruthComparison {
    /// Per true plane: the angle in degrees between its normal and the nearest trained plane's,
    /// and the centre distance as a fraction of the true plane's diagonal.
    planes: Vec<(f64, f64)>,
    /// PSNR of the transmission layer against the true transmission, mean over the test views.
    transmission_psnr: Option<f64>,
}

impl std::fmt::Display for TruthComparison {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for (i, (angle, centre)) in self.planes.iter().enumerate() {
            write!(
                f,
                "plane {i}: normal off by {angle:.2} deg, centre by {:.2}% of the size; ",
                100.0 * centre
            )?;
        }
        match self.transmission_psnr {
            Some(p) => write!(f, "transmission PSNR {p:.2} dB"),
            None => write!(f, "no true transmission images"),
        }
    }
}

fn compare_with_truth(
    trainer: &Trainer,
    data: &TrainingData,
    root: &Path,
) -> Result<Option<TruthComparison>> {
    let gt = root.join("gt");
    if !gt.is_dir() {
        return Ok(None);
    }
    let mut planes = Vec::new();
    let planes_path = gt.join("planes.json");
    if planes_path.is_file() {
        for spec in trgs_core::io::read_planes_json(&planes_path)? {
            let Some(truth) = spec.plane else { continue };
            let diag = truth.width.hypot(truth.height);
            let best = trainer
                .planes()
                .iter()
                .map(|p| {
                    let cos = p.unit_normal().dot(truth.unit_normal()).abs().min(1.0);
                    (cos.acos().to_degrees(), p.centre.distance(truth.centre) / diag)
                })
                .min_by(|a, b| a.1.total_cmp(&b.1));
            planes.push(best.unwrap_or((f64::NAN, f64::NAN)));
        }
    }
    let mut psnrs = Vec::new();
    for v in &data.test {
        let path = gt.join("transmission").join(&v.camera.name);
        if !path.is_file() {
            continue;
        }
        let truth = trgs_core::io::read_rgb_image(&path)?;
        let (w, h) = (v.camera.width(), v.camera.height());
        let truth = trgs_train::data::resize_area(&truth, w, h);
        let frame = trainer.render(&v.camera)?;
        let t = frame.read_layer(trainer.context(), Layer::Transmission);
        psnrs.push(psnr(&t, &truth)?);
    }
    let transmission_psnr =
        (!psnrs.is_empty()).then(|| psnrs.iter().sum::<f64>() / psnrs.len() as f64);
    Ok(Some(TruthComparison { planes, transmission_psnr }))
}

/// What a run measured besides the evaluations.
struct RunSummary<'a> {
    train_seconds: f64,
    /// Mean milliseconds per step of each phase.
    step_ms: Vec<(&'static str, f64)>,
    truth: Option<&'a TruthComparison>,
}

fn write_outputs(
    out: &Path,
    trainer: &Trainer,
    data: &TrainingData,
    last: &Evaluation,
    evaluations: &[Evaluation],
    run: &RunSummary,
) -> Result<()> {
    let gaussians = trainer.gaussians();
    write_ply(&out.join("model.ply"), &gaussians)?;
    write_planes_json(&out.join("planes.json"), trainer.planes())?;
    let renders = out.join("renders");
    let test = data.eval_views();
    // Render FPS at the training resolution: the mean over the test views.
    let t = Instant::now();
    for v in test {
        let frame = trainer.render(&v.camera)?;
        let color = frame.read_layer(trainer.context(), Layer::Color);
        let stem = Path::new(&v.camera.name)
            .file_stem()
            .map_or_else(|| v.camera.name.clone(), |s| s.to_string_lossy().into_owned());
        write_png_rgb(&renders.join(format!("{stem}.png")), &color)?;
    }
    let fps = test.len() as f64 / t.elapsed().as_secs_f64();
    let metrics = serde_json::json!({
        "psnr": last.psnr,
        "ssim": last.ssim,
        "views": last.views.iter().map(|(n, p, s)| serde_json::json!({"name": n, "psnr": p, "ssim": s})).collect::<Vec<_>>(),
        "train_seconds": run.train_seconds,
        "step_ms": run.step_ms.iter().map(|(k, v)| (k.to_string(), serde_json::json!(v))).collect::<serde_json::Map<_, _>>(),
        "steps": trainer.step,
        "gaussians": gaussians.len(),
        "render_fps": fps,
        "resolution": [data.size().0, data.size().1],
        "truth": run.truth,
        "psnr_over_time": evaluations.iter().map(|e| serde_json::json!({"step": e.step, "seconds": e.seconds, "psnr": e.psnr})).collect::<Vec<_>>(),
    });
    write_atomic(&out.join("metrics.json"), serde_json::to_string_pretty(&metrics)?.as_bytes())?;
    Ok(())
}
