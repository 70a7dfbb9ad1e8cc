//! `train`: a training run ([`trgs_train::run::TrainingRun`]) with a progress bar, and with
//! `--viewer` the live viewer fed from the run's events.
use anyhow::{Context, Result, bail};
use clap::parser::ValueSource;
use clap::{CommandFactory, Parser};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::time::Duration;
use trgs_train::checkpoint::CHECKPOINT_FILE;
use trgs_train::{RunConfig, RunEvent, RunOptions, RunSummary, TrainingRun};
use trgs_viewer::{LiveFeed, Snapshot, Source, ViewerOptions};

/// The shortest time between two snapshots for the viewer (each is a readback of the scene).
const SNAPSHOT_INTERVAL: Duration = Duration::from_millis(500);

/// TR-Gaussians training: Gaussians, reflection planes and their layers from a scene folder.
///
/// Writes <OUT>/: model.ply (INRIA layout), planes.json, cameras.json, metrics.json, renders of
/// the test views and their layers, log.jsonl, and checkpoint.trgs, which --resume continues
/// from. Without --data it trains on a built-in synthetic scene.
#[derive(Debug, Parser)]
#[command(
    name = "train",
    version,
    after_help = "Continue an interrupted run: trgs train --out DIR --resume"
)]
pub struct Args {
    /// Continue the run in --out from its checkpoint, with the settings it started with (only
    /// --target-memory may be given anew: it depends on the machine, not the training)
    #[arg(long)]
    resume: bool,
    /// Show training live in the viewer window (also with --resume); closing the window lets
    /// training go on
    #[arg(long)]
    viewer: bool,
    #[command(flatten)]
    config: RunConfig,
}

/// How the run starts.
enum Start {
    New(RunConfig),
    /// The run folder and the `--target-memory` given anew.
    Resume(PathBuf, Option<u64>),
}

/// The command line, refusing settings beside --resume (the run keeps its own) other than the
/// machine's (`RunOptions::target_memory`).
fn parse(matches: &clap::ArgMatches) -> Result<(Start, bool)> {
    let cli = super::parsed::<Args>(matches);
    if !cli.resume {
        let mut config = cli.config;
        let steps_given = matches.value_source("iterations") == Some(ValueSource::CommandLine);
        config.default_iterations_unless(steps_given);
        config.check()?;
        return Ok((Start::New(config), cli.viewer));
    }
    let given: Vec<String> = Args::command()
        .get_arguments()
        .filter(|a| !matches!(a.get_id().as_str(), "out" | "resume" | "viewer" | "target_memory"))
        .filter(|a| matches.value_source(a.get_id().as_str()) == Some(ValueSource::CommandLine))
        .filter_map(|a| a.get_long().map(|l| format!("--{l}")))
        .collect();
    if !given.is_empty() {
        bail!(
            "--resume continues a run with the settings it started with (only --target-memory \
             may be given anew); drop {}",
            given.join(" ")
        );
    }
    Ok((Start::Resume(cli.config.out, cli.config.target_memory), cli.viewer))
}

pub fn run(matches: &clap::ArgMatches) -> Result<()> {
    let (start, viewer) = parse(matches)?;
    let out = match &start {
        Start::New(config) => config.out.clone(),
        Start::Resume(out, _) => out.clone(),
    };
    ctrlc::set_handler(move || {
        eprintln!("\n{}", interrupted(&out));
        std::process::exit(130);
    })
    .context("setting up the Ctrl-C handler")?;
    if !viewer {
        return train(start, None);
    }
    // The window needs the main thread; training runs beside it and publishes snapshots.
    let feed = LiveFeed::new();
    let worker_feed = feed.clone();
    let worker = std::thread::Builder::new()
        .name("train".into())
        .spawn(move || {
            let result = train(start, Some(&worker_feed));
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

/// What an interrupted run in `out` leaves: its checkpoint is written whole or not at all, so
/// the last one stands (a write cut short leaves a temporary file that the next start removes).
fn interrupted(out: &Path) -> String {
    let resume = format!("`trgs train --out {} --resume` continues from it", out.display());
    match trgs_core::io::read_unfinished_run(out) {
        Some(r) if r.checkpoint_step > 0 => format!(
            "interrupted: the checkpoint of step {} of {} is saved in {}; {resume}",
            r.checkpoint_step,
            r.iterations,
            out.join(CHECKPOINT_FILE).display()
        ),
        Some(r) => format!(
            "interrupted before the first checkpoint of {} steps: nothing to continue from; a \
             new run in {} starts over",
            r.iterations,
            out.display()
        ),
        // Before the run marked its folder (loading), or while it wrote its final results.
        None if out.join(CHECKPOINT_FILE).is_file() => {
            format!("interrupted: {} is kept; {resume}", out.join(CHECKPOINT_FILE).display())
        }
        None => "interrupted before training started: nothing was saved".to_string(),
    }
}

/// A line above the progress bar (`ProgressBar::println` prints nothing when the bar is hidden,
/// as it is when the output is not a terminal).
fn say(bar: &ProgressBar, line: String) {
    bar.suspend(|| println!("{line}"));
}

/// Until the photos load (the built-in scene is written first), a line says the run is starting;
/// the photos load on several threads and the bar counts them (through the returned progress
/// callback), then gives way to the steps'.
fn loading_bar() -> (ProgressBar, impl Fn(usize, usize) + Sync) {
    let loading = ProgressBar::new_spinner();
    loading.set_message("starting the run");
    loading.enable_steady_tick(Duration::from_millis(200));
    let bar = loading.clone();
    let progress = move |done: usize, total: usize| {
        if bar.length() != Some(total as u64) {
            bar.set_style(
                ProgressStyle::with_template("loading photos {bar:40} {pos}/{len}  eta {eta}")
                    .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
            bar.set_length(total as u64);
        }
        bar.set_position(done as u64);
    };
    (loading, progress)
}

/// The run from its start or its checkpoint, its events shown on the terminal and, when a
/// viewer watches, published to `feed`.
fn train(start: Start, feed: Option<&LiveFeed>) -> Result<()> {
    let (loading, progress) = loading_bar();
    let options = |target_memory| RunOptions {
        progress: Some(&progress),
        target_memory,
        ..RunOptions::default()
    };
    let run = match start {
        Start::New(config) => TrainingRun::start(config, options(None)),
        Start::Resume(out, target_memory) => TrainingRun::resume(&out, options(target_memory)),
    };
    loading.finish_and_clear();
    let mut run = run?;
    if let Some(feed) = feed {
        feed.set_cameras(run.cameras());
        feed.set_folder(run.config().out.clone());
    }
    let iterations = run.config().iterations;
    let bar = ProgressBar::new(u64::from(iterations));
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} steps  {per_sec}  eta {eta}  {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_position(u64::from(run.trainer().step));
    bar.reset_eta();
    while let Some(event) = run.next_event() {
        match event? {
            RunEvent::Note(line) => say(&bar, line),
            RunEvent::Step(s) => {
                bar.set_position(u64::from(s.step));
                if s.stats.skipped {
                    say(
                        &bar,
                        format!(
                            "step {}: its frame outgrew the key list sized from earlier steps, so \
                             it changed nothing; the first step recorded after it is known (the \
                             one after next) is sized exactly",
                            s.step
                        ),
                    );
                }
                let (loss, psnr) = (s.stats.loss, s.stats.psnr);
                let ram = s.memory.peak_ram_bytes.map_or(String::new(), |b| {
                    format!("  RAM peak {}", trgs_train::human_bytes(b))
                });
                bar.set_message(format!(
                    "loss {loss:.4}  psnr {psnr:.2}  {} Gaussians  GPU {}{ram}",
                    s.gaussians,
                    trgs_train::human_bytes(s.memory.gpu.total())
                ));
                if let Some(feed) = feed
                    && feed.wants_snapshot(SNAPSHOT_INTERVAL)
                {
                    let status = format!(
                        "training: step {} of {iterations}, loss {loss:.4}, PSNR {psnr:.2} dB, {} \
                         Gaussians",
                        s.step, s.gaussians
                    );
                    feed.publish(snapshot(&run, status)?);
                }
            }
            RunEvent::PlaneCreated { label, plane: p } => {
                let (c, n) = (p.centre, p.unit_normal());
                say(
                    &bar,
                    format!(
                        "plane {label}: centre ({:.3}, {:.3}, {:.3}), normal ({:.3}, {:.3}, \
                         {:.3}), {:.2} x {:.2}",
                        c.x, c.y, c.z, n.x, n.y, n.z, p.width, p.height
                    ),
                );
            }
            RunEvent::PlaneFailed { label, reason } => {
                say(&bar, format!("plane {label}: not initialised: {reason}"));
            }
            RunEvent::Evaluation(e) => {
                // R0 is the one plane parameter the masks do not pin; show where it goes.
                let r0: Vec<_> =
                    run.trainer().planes().iter().map(|p| format!("{:.3}", p.r0())).collect();
                let planes =
                    if r0.is_empty() { String::new() } else { format!("; R0 {}", r0.join(", ")) };
                say(
                    &bar,
                    format!(
                        "step {}: PSNR {:.2} dB, SSIM {:.4} on the {} views ({:.0} s of \
                         training){planes}",
                        e.step,
                        e.psnr,
                        e.ssim,
                        run.data().eval_views_name(),
                        e.seconds
                    ),
                )
            }
            RunEvent::CheckpointWritten { .. } => {}
            RunEvent::Finished(summary) => {
                bar.finish();
                report(&summary, run.config().exposure.is_on());
                if let Some(feed) = feed {
                    // The final model, whatever the snapshot interval left the viewer with.
                    let status = format!("training finished: results in {}", summary.out.display());
                    feed.publish(snapshot(&run, status)?);
                }
            }
        }
    }
    Ok(())
}

/// The model now, for the viewer.
fn snapshot(run: &TrainingRun, status: String) -> Result<Snapshot> {
    let trainer = run.trainer();
    Ok(Snapshot {
        gaussians: trainer.gaussians()?,
        planes: trainer.planes().to_vec(),
        reflection: trainer.render_options().reflection,
        status,
    })
}

/// The closing lines: the ground truth's verdict, the phases of a step, the result (with the
/// exposure protocol's score when the run learnt exposures).
fn report(s: &RunSummary, exposure: bool) {
    if let (Some(t), Some(dir)) = (&s.truth, &s.truth_dir) {
        println!("against the ground truth in {}: {t}", dir.display());
    }
    let phases: Vec<String> = s.step_ms.iter().map(|(k, v)| format!("{k} {v:.1}")).collect();
    println!("ms per step: {}", phases.join(", "));
    println!(
        "done: {} steps in {:.0} s ({:.0} ms per step), test PSNR {:.2} dB, SSIM {:.4}; results \
         in {}",
        s.steps,
        s.train_seconds,
        1e3 * s.train_seconds / f64::from(s.steps.max(1)),
        s.last.psnr,
        s.last.ssim,
        s.out.display()
    );
    if let Some(h) = s.last.right_half.filter(|_| exposure) {
        println!(
            "test views' right halves: PSNR {:.2} dB through the exposure fitted on each photo's \
             left half ({:.2} dB as rendered)",
            h.psnr_exposure_fitted, h.psnr
        );
    }
}
