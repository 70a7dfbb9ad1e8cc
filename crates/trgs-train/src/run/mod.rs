//! A whole training run as a library type: [`TrainingRun`] owns the dataset, the trainer, the
//! three stages and the plane initialisation at the end of stage 1, the densification schedule,
//! evaluations, checkpoints and resume, the JSONL log and the final outputs. It reports what
//! happens as [`RunEvent`]s, which the `train` command's progress bar, the live viewer and an
//! embedding app consume alike.
//!
//! ```
//! use trgs_synthetic::{SyntheticConfig, generate, write_dataset};
//! use trgs_train::{RunConfig, RunEvent, RunOptions, TrainingRun};
//!
//! let dir = trgs_core::scratch::ScratchDir::new("run-doc-example");
//! write_dataset(&generate(&SyntheticConfig::small()), &dir.join("scene"))?; // a glass scene
//! let config = RunConfig { data: Some(dir.join("scene")), out: dir.join("run"), iterations: 40,
//!                          ..RunConfig::default() };
//! let mut run = TrainingRun::start(config, RunOptions::default())?;
//! while let Some(event) = run.next_event() {
//!     match event? {
//!         RunEvent::PlaneCreated { label, plane } => println!("plane {label}: {:.2}", plane.r0()),
//!         RunEvent::Finished(summary) => println!("test PSNR {:.2} dB", summary.last.psnr),
//!         _ => {}
//!     }
//! }
//! let frame = run.trainer().render(&run.data().test[0].camera)?; // every layer of a test view
//! let image = frame.read_layer(run.trainer().context(), trgs_render::Layer::Color)?;
//! assert_eq!((run.trainer().planes().len(), image.width), (1, 64));
//! # Ok::<(), anyhow::Error>(())
//! ```
mod arg_parsers;
mod candidates;
pub mod checkpoint;
mod config;
mod events;
mod folder;
mod glass_pixels;
mod log;
mod options;
mod outputs;
mod plane_refit;
mod plane_trial;
mod refit_offset;
mod refit_wall;
mod scene;
mod state;
mod steps;

pub use arg_parsers::{parse_image_size, parse_non_negative, parse_positive, parse_positive_share};
pub use candidates::{CandidateRecord, PlaneTrial};
pub use config::{
    Ablations, CAPTURE_ITERATIONS, DEFAULT_MCMC_CAP, DEMO_ITERATIONS, DemoScene, DensifyMode,
    ExposureMode, PlaneSource, RunConfig, upgrade_config_record,
};
pub use events::{RunEvent, StepEvent, StepMemory};
pub use folder::LOCK_FILE;
pub use log::LOG_FILE;
pub use options::RunOptions;
pub use outputs::RunSummary;
pub use plane_trial::opaque_centres;
pub use scene::DEMO_SCENE_MARKER;
pub use state::RunState;

use crate::data::{LoadProgress, TrainingData};
use crate::gaussians::init::{gaussians_from_points, seed_points};
use crate::planes::adam::OffsetLimit;
use crate::planes::init::{PlaneInitSettings, initialise_planes};
use crate::planes::reflection_seed::{ReflectedSpaceSeeds, mirrored_seeds, reflected_space_seeds};
use crate::trainer::{StepTimes, Trainer};
use anyhow::{Context, Result, bail};
use checkpoint::{CHECKPOINT_FILE, Checkpoint, read_checkpoint, write_checkpoint};
use folder::RunLock;
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use trgs_core::fit::SilhouetteSettings;
use trgs_core::io::{
    UnfinishedRun, clear_unfinished_run, remove_stale_temporaries, write_cameras_json,
    write_unfinished_run,
};
use trgs_core::rng::Rng;
use trgs_core::scene::{Camera, Gaussians, ReflectionPlane};
use trgs_render::GpuContext;

/// A training run from its start or from a checkpoint (see the module docs).
#[derive(Debug)]
pub struct TrainingRun {
    data_dir: PathBuf,
    data: TrainingData,
    trainer: Trainer,
    state: RunState,
    rng: Rng,
    log: log::RunLog,
    /// When the run started, less the seconds of the run before a resume.
    t0: Instant,
    eval_every: u32,
    checkpoint_every: u32,
    /// Resumed from the checkpoint of a run that had finished: its results are written again.
    was_finished: bool,
    events: VecDeque<RunEvent>,
    /// The step recorded last, not yet finished (see `advance`).
    in_flight: Option<steps::InFlight>,
    done: bool,
    /// The run folder, held for this run alone until it has finished or failed.
    lock: Option<RunLock>,
}

impl TrainingRun {
    /// A new run of `config` (setting a previous run's files in the same folder aside). A run
    /// refused before it starts leaves no folder behind that it made itself.
    pub fn start(mut config: RunConfig, options: RunOptions<'_>) -> Result<Self> {
        // Refused before the device is set up.
        config.check()?;
        let out = config.out.clone();
        let made_folder = !out.exists();
        let lock = RunLock::acquire(&out)?;
        if let Some(mib) = options.target_memory {
            config.target_memory = Some(mib);
        }
        let begun = match options.context {
            Some(ctx) => Ok(ctx),
            None => GpuContext::new().map_err(anyhow::Error::from),
        }
        .and_then(|ctx| {
            let silent = |_: usize, _: usize| {};
            let progress = options.progress.unwrap_or(&silent);
            Self::begin(ctx, lock, config, None, Vec::new(), progress)
        });
        if begun.is_err() && made_folder {
            folder::remove_if_only_the_lock(&out);
        }
        begun
    }

    /// Continue the run in `out` from its checkpoint, with the settings it started with.
    pub fn resume(out: &Path, options: RunOptions<'_>) -> Result<Self> {
        let lock = RunLock::acquire(out)?;
        // Refused before the device is set up.
        let (ck, state, path) = checkpoint_to_resume(out)?;
        let ctx = match options.context {
            Some(ctx) => ctx,
            None => GpuContext::new()?,
        };
        let silent = |_: usize, _: usize| {};
        let progress = options.progress.unwrap_or(&silent);
        Self::resume_on(ctx, lock, (ck, state, path), options.target_memory, progress)
    }

    fn resume_on(
        ctx: GpuContext,
        lock: RunLock,
        (ck, mut state, path): (Checkpoint, RunState, PathBuf),
        target_memory: Option<u64>,
        loading: &LoadProgress<'_>,
    ) -> Result<Self> {
        if let Some(mib) = target_memory {
            state.config.target_memory = Some(mib);
        }
        let note = if ck.step >= state.config.iterations {
            format!(
                "{}: the run finished at step {}; writing its results again",
                path.display(),
                ck.step
            )
        } else {
            format!(
                "resuming {} at step {} of {}",
                path.display(),
                ck.step,
                state.config.iterations
            )
        };
        let config = state.config.clone();
        Self::begin(ctx, lock, config, Some((ck, state)), vec![RunEvent::Note(note)], loading)
    }

    fn begin(
        ctx: GpuContext,
        lock: RunLock,
        config: RunConfig,
        resumed: Option<(Checkpoint, RunState)>,
        mut events: Vec<RunEvent>,
        loading: &LoadProgress<'_>,
    ) -> Result<Self> {
        let mut note = |line: String| events.push(RunEvent::Note(line));
        let (data_dir, written) = scene::dataset_dir(&config)?;
        written.into_iter().for_each(&mut note);
        let data = scene::load_data(&ctx, &config, &data_dir, &mut note, loading)?;
        // Created when the lock was taken.
        let out = config.out.clone();
        let was_finished = resumed.as_ref().is_some_and(|(ck, _)| ck.step >= config.iterations);
        remove_stale_temporaries(&out, &folder::RUN_FILES);
        let settings = config.settings();
        let densification = config.densification();
        let (mut trainer, state, log) = match resumed {
            Some((ck, mut state)) => {
                state.check_same_views(&data, &data_dir)?;
                // A checkpoint from before the names were kept: they are known good now.
                if state.train_views.is_empty() {
                    state.train_views = view_names(&data);
                }
                if state.train_cameras.is_empty() {
                    state.train_cameras = state::camera_records(&data);
                }
                let log = log::RunLog::resume(&out, ck.step)?;
                let mut trainer =
                    Trainer::from_checkpoint(&ctx, &ck, settings, data.extent, &densification)?;
                if let Some(end) = state.stage1_end {
                    trainer.settings.stage1 = end;
                }
                if let Some(trial) = &state.trial {
                    plane_trial::hold_perturbation_for(&mut trainer.settings, trial);
                }
                (trainer, state, log)
            }
            None => new_run_state(&ctx, &config, &data, &mut note)?,
        };
        if !was_finished {
            let checkpoint_step = trainer.step;
            let iterations = config.iterations;
            write_unfinished_run(&out, &UnfinishedRun { iterations, checkpoint_step })?;
        }
        trainer.profile = config.profile;
        let budget = crate::trainer::targets::budget_bytes(&ctx, config.target_memory);
        trainer.set_target_budget(budget);
        let photos: u64 = data.train.iter().map(crate::trainer::targets::target_bytes).sum();
        if photos > budget {
            note(format!(
                "the training views need {} MiB on the GPU, over its budget of {} MiB \
                 (--target-memory): they are streamed, each uploaded a step ahead",
                photos.div_ceil(1 << 20),
                budget >> 20
            ));
        }
        let cameras: Vec<_> = data.train.iter().map(|v| v.camera.clone()).collect();
        trainer.set_training_cameras(&cameras);
        let run = Self {
            rng: Rng::from_state(state.rng_state),
            eval_every: config.eval_every.unwrap_or((config.iterations / 10).max(1)),
            checkpoint_every: config
                .checkpoint_every
                .or(config.eval_every)
                .unwrap_or((config.iterations / 10).max(1)),
            t0: Instant::now()
                .checked_sub(Duration::from_secs_f64(state.seconds))
                .unwrap_or_else(Instant::now),
            data_dir,
            data,
            trainer,
            state,
            log,
            was_finished,
            events: events.into(),
            in_flight: None,
            done: false,
            lock: Some(lock),
        };
        // Every view once, as the INRIA code writes it: viewers snap to these.
        write_cameras_json(&out.join("cameras.json"), &run.cameras())?;
        Ok(run)
    }

    /// The next event, running the next step (or the final outputs) when none is waiting; None
    /// once the run has finished or failed. A failed step loses nothing saved: the error says
    /// how to continue from the last checkpoint.
    pub fn next_event(&mut self) -> Option<Result<RunEvent>> {
        // A pipelined step reports the step before it: the first reports nothing.
        while self.events.is_empty() && !self.done {
            let progress = if self.trainer.step < self.config().iterations {
                self.advance()
            } else {
                self.finish()
            };
            if let Err(e) = progress {
                // Events of the failed step are not reported after its error.
                self.events.clear();
                self.done = true;
                self.lock = None;
                return Some(Err(e));
            }
        }
        if self.done {
            // Nothing more is written: the folder is free for a resume or a new run.
            self.lock = None;
        }
        self.events.pop_front().map(Ok)
    }

    /// Run to the end, passing every event to `on_event`.
    pub fn run_to_end(&mut self, mut on_event: impl FnMut(&RunEvent)) -> Result<RunSummary> {
        let mut summary = None;
        while let Some(event) = self.next_event() {
            let event = event?;
            on_event(&event);
            if let RunEvent::Finished(s) = event {
                summary = Some(s);
            }
        }
        summary.context("the run had finished already")
    }

    pub fn config(&self) -> &RunConfig {
        &self.state.config
    }

    pub fn trainer(&self) -> &Trainer {
        &self.trainer
    }

    /// The trainer, to adjust between steps (a densification strategy of the app's own,
    /// [`Trainer::set_strategy`]; its profiling). A checkpoint keeps what the run's
    /// configuration says, not such changes.
    pub fn trainer_mut(&mut self) -> &mut Trainer {
        &mut self.trainer
    }

    /// The dataset at the training resolution.
    pub fn data(&self) -> &TrainingData {
        &self.data
    }

    /// The scene folder trained on.
    pub fn data_dir(&self) -> &Path {
        &self.data_dir
    }

    /// Every view of the dataset, training views first (the run folder's cameras.json).
    pub fn cameras(&self) -> Vec<Camera> {
        let train = self.data.train.iter().map(|v| v.camera.clone());
        train.chain(self.data.test.iter().map(|v| v.camera.clone())).collect()
    }

    /// A new epoch's view order (a shuffle of the training views, less those a plane trial
    /// holds out) once the last one is used up.
    fn draw_epoch_if_done(&mut self) {
        if self.state.order.is_empty() {
            let held_out = self.state.trial.as_ref().map_or(&[][..], |t| &t.held_out[..]);
            self.state.order =
                (0..self.data.train.len()).filter(|i| !held_out.contains(i)).collect();
            for i in (1..self.state.order.len()).rev() {
                self.state.order.swap(i, self.rng.below(i + 1));
            }
        }
    }

    /// Whether the run has finished (or failed): no more events will come.
    pub fn is_done(&self) -> bool {
        self.done && self.events.is_empty()
    }

    /// The final checkpoint and outputs.
    fn finish(&mut self) -> Result<()> {
        // The last step is taken whole; nothing is in flight by now.
        self.finish_in_flight()?;
        // The finished state, so that `--resume` after the end writes the same results again
        // instead of training on from the last intermediate checkpoint.
        if !self.was_finished {
            self.save_checkpoint()?;
        }
        let summary =
            outputs::write_outputs(&self.trainer, &self.data, &self.data_dir, &self.state)?;
        clear_unfinished_run(&self.config().out)?;
        self.events.push_back(RunEvent::Finished(summary));
        self.done = true;
        Ok(())
    }

    /// Write the checkpoint: the trainer's state and the run's own.
    fn save_checkpoint(&mut self) -> Result<()> {
        self.state.rng_state = self.rng.state();
        self.state.seconds = self.t0.elapsed().as_secs_f64();
        let extra = serde_json::to_value(&self.state)?;
        let path = self.config().out.join(CHECKPOINT_FILE);
        write_checkpoint(&path, &self.trainer.checkpoint(extra)?)?;
        self.log.flush()?;
        let step = self.trainer.step;
        let iterations = self.config().iterations;
        let marker = UnfinishedRun { iterations, checkpoint_step: step };
        write_unfinished_run(&self.config().out, &marker)?;
        self.events.push_back(RunEvent::CheckpointWritten { step, path });
        Ok(())
    }

    /// Initialise the planes from the glass masks (the end of stage 1).
    fn init_planes(&mut self) -> Result<()> {
        let gaussians = self.trainer.gaussians()?;
        let init = initialise_planes(
            &gaussians,
            &self.data.train,
            &self.data.materials,
            self.data.extent,
            &PlaneInitSettings {
                silhouette: (!self.config().no_mask_refinement).then(SilhouetteSettings::default),
                ..PlaneInitSettings::default()
            },
            &mut self.rng,
        );
        for (label, reason) in &init.failed {
            self.events.push_back(RunEvent::PlaneFailed { label: *label, reason: reason.clone() });
        }
        for (&label, plane) in init.labels.iter().zip(&init.planes) {
            self.events.push_back(RunEvent::PlaneCreated { label, plane: *plane });
        }
        for (&label, text) in init.labels.iter().zip(&init.refined) {
            self.events.push_back(RunEvent::Note(format!("plane {label}: {text}")));
        }
        let names: Vec<String> = init.labels.iter().map(|l| format!("plane {l}")).collect();
        self.add_planes_with_seeds(
            &gaussians,
            &init.planes,
            &names,
            &init.offset_limits,
            init.glass,
        )
    }

    /// Add `planes` (named in notes by `names`), their offset limits and glass Gaussians to the
    /// trainer, with the reflection seeds of each unless switched off: the stage-1 Gaussians
    /// `gaussians` seen through a plane mirrored to its front, and seeds in the space it
    /// reflects.
    fn add_planes_with_seeds(
        &mut self,
        gaussians: &Gaussians<f32>,
        planes: &[ReflectionPlane],
        names: &[String],
        limits: &[Option<OffsetLimit>],
        mut added: Gaussians<f32>,
    ) -> Result<()> {
        if !self.config().no_reflection_seeds {
            let cameras: Vec<_> = self.data.train.iter().map(|v| v.camera.clone()).collect();
            // One margin for both seed sources.
            let space_settings = ReflectedSpaceSeeds::default();
            let seeds = mirrored_seeds(gaussians, planes, &cameras, space_settings.margin);
            let views: Vec<_> = self.data.train.iter().map(|v| (&v.camera, &v.image)).collect();
            let space = reflected_space_seeds(
                &views,
                planes,
                self.data.extent,
                &space_settings,
                gaussians.sh_degree,
                &mut self.rng,
            );
            for ((name, s), r) in names.iter().zip(&seeds).zip(&space) {
                self.events.push_back(RunEvent::Note(format!(
                    "{name}: {} Gaussians seen through it mirrored to its front, {} seeded in \
                     the space it reflects",
                    s.len(),
                    r.len()
                )));
                added.append(s);
                added.append(r);
            }
        }
        let added_count = added.len();
        let dropped = self.trainer.add_planes(planes, limits, &added)?;
        if dropped > 0 {
            self.events.push_back(RunEvent::Note(format!(
                "the planes' {added_count} Gaussians would pass --cap: the {dropped} least opaque \
                 were dropped"
            )));
        }
        Ok(())
    }
}

/// The trainer, state and log of a new run of `config` on `data`, the previous run's files in
/// its folder set aside.
fn new_run_state(
    ctx: &GpuContext,
    config: &RunConfig,
    data: &TrainingData,
    note: &mut impl FnMut(String),
) -> Result<(Trainer, RunState, log::RunLog)> {
    let mut rng = Rng::new(config.seed);
    let (seeds, said) =
        seed_points(&data.points, data.centre, data.extent, config.random_init, &mut rng);
    said.into_iter().for_each(&mut *note);
    let densification = config.densification();
    let gaussians = gaussians_from_points(&seeds, config.sh_degree, densification.initial_shape());
    let mut trainer = Trainer::new(ctx, &gaussians, &[], config.settings(), data.extent)?;
    trainer.set_densification(&densification)?;
    // A previous run's files in this folder would pass as this run's (and its checkpoint be
    // what `--resume` continues) if this run stopped early.
    let out = &config.out;
    if let Some((aside, moved)) = folder::set_aside_previous_run(out)? {
        note(format!(
            "a new run in {}: the previous run's files ({}) were moved to {}",
            out.display(),
            moved.join(", "),
            aside.display()
        ));
    }
    let state = RunState {
        config: config.clone(),
        rng_state: rng.state(),
        order: Vec::new(),
        evaluations: Vec::new(),
        train_seconds: 0.0,
        seconds: 0.0,
        phase_ms: StepTimes::default(),
        train_views: view_names(data),
        train_cameras: state::camera_records(data),
        peak_gpu_bytes: 0,
        skipped_steps: 0,
        candidates: Vec::new(),
        next_proposal: (config.planes == Some(PlaneSource::Auto))
            .then_some(trainer.settings.stage1),
        stage1_end: None,
        trial: None,
        candidate_seconds: 0.0,
    };
    Ok((trainer, state, log::RunLog::create(out)?))
}

/// The checkpoint `--resume` continues in `out`, the run's state it holds, and its path; a
/// missing one, a folder in its place, one that cannot be read and one past its run's end are
/// told apart.
fn checkpoint_to_resume(out: &Path) -> Result<(Checkpoint, RunState, PathBuf)> {
    let path = out.join(CHECKPOINT_FILE);
    if let Err(e) = std::fs::symlink_metadata(&path)
        && e.kind() == std::io::ErrorKind::NotFound
    {
        bail!(
            "--resume: no checkpoint to continue from in {} ({CHECKPOINT_FILE} is missing: the \
             run stopped before its first checkpoint, or this is not its folder)",
            out.display()
        );
    }
    if path.is_dir() {
        bail!("--resume: {} is a folder, not a checkpoint file", path.display());
    }
    let ck = read_checkpoint(&path)
        .with_context(|| format!("--resume: the checkpoint in {} cannot be read", out.display()))?;
    let mut state = RunState::of_checkpoint(&ck, &path)?;
    state.config.out = out.to_path_buf();
    if ck.step > state.config.iterations {
        bail!(
            "{}: the checkpoint is at step {}, past the {} steps of the run it records: it is \
             not this run's, or it was changed",
            path.display(),
            ck.step,
            state.config.iterations
        );
    }
    Ok((ck, state, path))
}

fn view_names(data: &TrainingData) -> Vec<String> {
    data.train.iter().map(|v| v.camera.name.clone()).collect()
}
