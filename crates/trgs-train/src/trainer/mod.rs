//! One training step on the GPU: render the view, the image loss and its gradient, the backward
//! pass, then Adam on every attribute buffer in place (the Gaussians never leave the GPU) and on
//! the planes (a few numbers each, on the CPU), then the densification strategy's maintenance.
//! The whole run (stages, plane initialisation, evaluation, checkpoints) is
//! [`crate::run::TrainingRun`]; this is the step it repeats.
use crate::densify::{Densification, DensifyEvent, DensifyStrategy, NoDensification};
use crate::exposure::ViewExposures;
use crate::exposure::stage::ExposureKernels;
use crate::gaussians::adam::Adam;
use crate::gaussians::plan::{Geometry, RowPlan, TrainState};
use crate::gaussians::state::GaussianState;
use crate::losses::LossKernels;
use crate::run::checkpoint::{Checkpoint, PlaneMoments};
use crate::settings::TrainSettings;
use targets::TargetCache;

pub mod memory;
mod phase_clock;
mod planes;
mod step;
mod step_times;
pub mod targets;

pub use step::StepInFlight;
pub use step_times::StepTimes;

use anyhow::{Context, Result};
use trgs_core::pipeline::AdamSettings;
use trgs_core::rng::Rng;
use trgs_core::scene::{Camera, Gaussians, ReflectionPlane};
use trgs_render::{Frame, GpuContext, GpuScene, LayerGrads, RenderOptions, Renderer};

/// What one step measured and did.
#[derive(Clone, Debug, PartialEq)]
pub struct StepStats {
    /// The step's number, counted from 1.
    pub step: u32,
    pub loss: f64,
    pub l1: f64,
    pub ssim: f64,
    /// PSNR of the rendered training view.
    pub psnr: f64,
    /// Tile keys of the step's frame, every view's together ([`trgs_render::Frame::key_count`]):
    /// what the sort orders and the rasterize passes walk, paged past one binding.
    pub keys: u64,
    /// The step's frame outgrew its key list (sized from earlier frames): its updates changed
    /// nothing (the step's guard), and the next frame recorded is sized exactly (in a
    /// pipelined loop the step after next: the next one was recorded before this was known,
    /// and may be skipped too). Only a step finished after the next was recorded can be
    /// skipped: [`Trainer::train_step`] takes it again.
    pub skipped: bool,
    /// How many times recording the step waited for the GPU ([`GpuContext::waits`]): none,
    /// unless its key list was sized exactly (the first step, the first recorded after a skipped
    /// step was known, the one after an edit of the set from outside the maintenance), phases
    /// are timed, or the adapter is a CPU one (which waits at the end of each phase:
    /// `Capabilities::records_while_busy`).
    pub record_waits: u64,
    /// Where the step's wall-clock time went.
    pub times: StepTimes,
    /// With [`Trainer::profile`]: GPU milliseconds of every stage of the step (render, losses,
    /// backward, the densification statistics and Adam), from timestamp queries (empty when off
    /// or when the adapter has none). The maintenance after the step is not included.
    pub gpu_stages: Vec<(&'static str, f64)>,
    /// What the densification strategy did to the set after the step (usually nothing): in a
    /// pipelined loop, what was applied then ([`Trainer::maintain`]: a densification decided
    /// after the step before), after what an edit applied since the last report.
    pub densified: Vec<DensifyEvent>,
    /// Gaussians whose opacity the perturbation changed after this step (0 on most steps; in
    /// a pipelined loop, reported a step late as the densification is).
    pub perturbed: usize,
}

/// The optimisation state on the GPU.
#[derive(Debug)]
pub struct Trainer {
    ctx: GpuContext,
    renderer: Renderer,
    gaussians: GaussianState,
    adam: Adam,
    plane_moments: Vec<PlaneMoments>,
    /// The training views' exposures (identity and never stepped when compensation is off).
    exposures: ViewExposures,
    /// Stages `exposure` and `exposure_bwd`, built when the settings turn compensation on.
    exposure_kernels: Option<ExposureKernels>,
    frame: Frame,
    losses: LossKernels,
    /// The training views' images and glass labels on the GPU, under a memory budget.
    targets: TargetCache,
    /// dL/d(layer) buffers, reused while the frame size and plane count stay.
    layer_grads: Option<((u32, u32, usize), LayerGrads)>,
    /// Steps taken so far.
    pub step: u32,
    pub settings: TrainSettings,
    /// The scene extent (scales the position and plane-centre rates).
    pub extent: f64,
    /// How the set changes: none, classic or MCMC ([`Trainer::set_densification`]).
    densification: Box<dyn DensifyStrategy>,
    /// Densification's and the perturbation's random draws.
    rng: Rng,
    /// Time every GPU stage of each step with timestamp queries ([`StepStats::gpu_stages`]).
    pub profile: bool,
    /// Wait for the GPU at the end of each phase of a step, so that [`StepTimes`] gives each
    /// phase its GPU time (the step then waits where it otherwise would not).
    pub time_phases: bool,
    /// The word that lets a step's updates change the model ([`crate::losses::step_guard`]).
    guard: crate::losses::step_guard::StepGuard,
    /// Size the next frame's key list exactly (after a frame outgrew its list, or an edit of
    /// the set from outside the maintenance; the maintenance's changes scale the list instead).
    exact_keys_next: bool,
    /// Centres of the training cameras (the opacity perturbation selects what they see through
    /// a plane).
    camera_centres: Vec<glam::DVec3>,
    /// The opacity perturbation's kernel (stage `perturb`).
    perturb: crate::planes::perturb::GpuPerturb,
    /// The count of a perturbation on its way back (reported when the maintenance settles).
    pending_perturbed: Option<trgs_render::toolkit::gpu::PendingRead>,
    /// What an edit from outside the maintenance applied on its way (a change the maintenance
    /// had left pending, and the perturbation's count): reported by the next
    /// [`Trainer::maintain`] or [`Trainer::settle`], so that every change is reported once.
    unreported: (Vec<DensifyEvent>, usize),
}

impl Trainer {
    /// Upload `gaussians` and `planes` and start from zero moments, without densification.
    pub fn new(
        ctx: &GpuContext,
        gaussians: &Gaussians<f32>,
        planes: &[ReflectionPlane],
        settings: TrainSettings,
        extent: f64,
    ) -> Result<Self> {
        trgs_render::toolkit::gpu::scoped(ctx, "setting up training", || {
            let state = GaussianState::new(ctx, gaussians, planes)?;
            Ok(Self::with_state(ctx, state, settings, extent))
        })
    }

    /// A trainer of `gaussians` (their planes' moments zero), without densification.
    fn with_state(
        ctx: &GpuContext,
        gaussians: GaussianState,
        settings: TrainSettings,
        extent: f64,
    ) -> Self {
        Self {
            ctx: ctx.clone(),
            renderer: Renderer::new(ctx),
            adam: Adam::new(ctx, AdamSettings::default()),
            plane_moments: vec![PlaneMoments::default(); gaussians.scene().planes().len()],
            exposures: ViewExposures::default(),
            exposure_kernels: settings.exposure.map(|_| ExposureKernels::new(ctx)),
            gaussians,
            frame: Frame::default(),
            losses: LossKernels::new(ctx),
            targets: TargetCache::new(targets::budget_bytes(ctx, None)),
            layer_grads: None,
            step: 0,
            rng: Rng::new(settings.seed ^ 0x5eed),
            settings,
            extent,
            densification: Box::new(NoDensification),
            profile: false,
            time_phases: false,
            guard: crate::losses::step_guard::StepGuard::new(ctx),
            exact_keys_next: false,
            camera_centres: Vec::new(),
            perturb: crate::planes::perturb::GpuPerturb::new(ctx),
            pending_perturbed: None,
            unreported: (Vec::new(), 0),
        }
    }

    /// Continue from `ck` (written by [`Trainer::checkpoint`]) with `settings`, which should be
    /// those of the interrupted run, and its densification (its statistics from `ck`).
    pub fn from_checkpoint(
        ctx: &GpuContext,
        ck: &Checkpoint,
        settings: TrainSettings,
        extent: f64,
        densification: &Densification,
    ) -> Result<Self> {
        trgs_render::toolkit::gpu::scoped(ctx, "resuming from a checkpoint", || {
            let state = GaussianState::from_state(ctx, &ck.state, &ck.planes)?;
            let mut t = Self::with_state(ctx, state, settings, extent);
            t.plane_moments = ck.plane_moments.clone();
            t.exposures = ck.exposures.clone();
            t.step = ck.step;
            t.rng = Rng::from_state(ck.rng_state);
            let n = ck.state.gaussians.len();
            t.densification = densification.strategy(ctx, n, ck.densify_stats.as_ref());
            Ok(t)
        })
    }

    /// Everything needed to continue this run later, with `extra` for the caller's own state.
    /// Finish a step in flight first ([`Trainer::finish_step`]): its plane gradients are not
    /// applied before; and settle the maintenance ([`Trainer::settle`]): a pending change of the
    /// set is refused here.
    pub fn checkpoint(&self, extra: serde_json::Value) -> Result<Checkpoint> {
        anyhow::ensure!(
            !self.densification.pending(),
            "a change of the set is pending: settle the maintenance before a checkpoint"
        );
        Ok(Checkpoint {
            step: self.step,
            state: self.read_state()?,
            planes: self.planes().to_vec(),
            plane_moments: self.plane_moments.clone(),
            exposures: self.exposures.clone(),
            densify_stats: self.densification.statistics()?,
            rng_state: self.rng.state(),
            extra,
        })
    }

    /// Densify with `densification` from now on (replacing the strategy in use, once a change
    /// it left pending is applied: the next [`Trainer::maintain`] or [`Trainer::settle`]
    /// reports it).
    pub fn set_densification(&mut self, densification: &Densification) -> Result<()> {
        self.settle_unreported()?;
        self.densification = densification.strategy(&self.ctx, self.gaussians.len(), None);
        Ok(())
    }

    /// Densify with `strategy` from now on: a strategy of the app's own (the built-in ones come
    /// from [`Trainer::set_densification`]), once a change the one in use left pending is
    /// applied (reported as by [`Trainer::set_densification`]).
    pub fn set_strategy(&mut self, strategy: Box<dyn DensifyStrategy>) -> Result<()> {
        self.settle_unreported()?;
        self.densification = strategy;
        Ok(())
    }

    /// The strategy in use.
    pub fn densification(&self) -> &dyn DensifyStrategy {
        self.densification.as_ref()
    }

    /// The training cameras (for the opacity perturbation; without them it perturbs nothing).
    pub fn set_training_cameras(&mut self, cameras: &[Camera]) {
        self.camera_centres = cameras.iter().map(|c| c.pose.centre()).collect();
    }

    /// The training views' exposures (identity when compensation is off).
    pub fn exposures(&self) -> &ViewExposures {
        &self.exposures
    }

    /// Bytes of the GPU buffers this trainer holds, by what they hold.
    pub fn gpu_memory(&self) -> memory::GpuMemory {
        use trgs_core::scene::Attribute;
        let scene = self.gaussians.scene();
        let m = self.gaussians.moments();
        let layer_grads = self.layer_grads.as_ref().map_or(0, |(_, g)| {
            [&g.color, &g.reflection, &g.strength, &g.transmission, &g.geometry, &g.reflection_raw]
                .iter()
                .map(|b| b.size())
                .sum()
        });
        memory::GpuMemory {
            parameters: Attribute::ALL.iter().map(|&a| scene.parameter(a).size()).sum::<u64>()
                + scene.populations().size(),
            moments: Attribute::ALL.iter().map(|&a| m[a].m.size() + m[a].v.size()).sum(),
            frame: self.frame.memory_bytes(),
            losses: self.losses.scratch_bytes() + layer_grads,
            targets: self.targets.counts().resident_bytes,
        }
    }

    /// The training views' GPU targets (their budget, uploads and evictions).
    pub fn targets(&self) -> &TargetCache {
        &self.targets
    }

    /// Hold at most `bytes` of training views on the GPU (the rest stream,
    /// [`Trainer::prefetch`]).
    pub fn set_target_budget(&mut self, bytes: u64) {
        self.targets.set_budget(bytes);
    }

    /// Queue `view`'s upload ahead of the step that trains on it (when it is not resident).
    pub fn prefetch(&mut self, view: &crate::data::View) -> Result<()> {
        let ctx = self.ctx.clone();
        // Outside a step's scope: an allocation that fails (a GPU out of memory) is an error
        // that says so, not wgpu's panic.
        trgs_render::toolkit::gpu::scoped(&ctx, "uploading a training view", || {
            self.targets.prefetch(&ctx, view).map_err(anyhow::Error::from)
        })
        .with_context(|| format!("uploading view {}", view.camera.name))
    }

    /// The parameters and Adam moments, read back (without a change of the set still pending,
    /// [`Trainer::settle`]).
    pub fn read_state(&self) -> Result<TrainState> {
        self.gaussians.read()
    }

    /// Replace the parameters and moments (after an edit such as densification); the strategy's
    /// per-Gaussian statistics start over, and a change of the set its maintenance left pending
    /// is dropped (it was decided for the set replaced: settle first to keep it).
    pub fn set_state(&mut self, state: &TrainState) -> Result<()> {
        let ctx = self.ctx.clone();
        trgs_render::toolkit::gpu::scoped(&ctx, "uploading the training state", || {
            // A change still pending was decided for the set replaced here: `restart` drops it.
            self.gaussians.replace(state)?;
            self.densification.restart(state.gaussians.len());
            self.exact_keys_next = true;
            Ok(())
        })
    }

    /// The attributes densification decides from, read back.
    pub fn geometry(&self) -> Result<Geometry> {
        self.gaussians.geometry()
    }

    /// Edit the set with its shared operations, the trainer's random state and the scene extent
    /// (what a strategy's maintenance gets), outside the schedule: tests and benchmarks run a
    /// strategy's steps this way. A change the maintenance left pending is applied first (the
    /// next [`Trainer::maintain`] or [`Trainer::settle`] reports it); the strategy in use starts
    /// its statistics over.
    pub fn edit_gaussians<R>(
        &mut self,
        edit: impl FnOnce(&mut GaussianState, &mut Rng, f64) -> Result<R>,
    ) -> Result<R> {
        // The edit sees the set with any change still pending applied.
        self.settle_unreported()?;
        let out = edit(&mut self.gaussians, &mut self.rng, self.extent)?;
        self.densification.restart(self.gaussians.len());
        self.exact_keys_next = true;
        Ok(out)
    }

    /// Rebuild the set by `plan` on the GPU (stage `gather_rows`).
    pub fn apply_plan(&mut self, plan: &RowPlan) -> Result<()> {
        self.edit_gaussians(|g, _, _| g.apply_plan(plan))
    }

    /// [`Trainer::apply_plan`] through the CPU (the twin), for tests and the benchmark.
    pub fn apply_plan_on_cpu(&mut self, plan: &RowPlan) -> Result<()> {
        self.edit_gaussians(|g, _, _| g.apply_plan_on_cpu(plan))
    }

    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    pub fn renderer(&self) -> &Renderer {
        &self.renderer
    }

    pub fn scene(&self) -> &GpuScene {
        self.gaussians.scene()
    }

    /// The current Gaussians, read back from the GPU.
    pub fn gaussians(&self) -> Result<Gaussians<f32>> {
        self.gaussians.gaussians()
    }

    pub fn planes(&self) -> &[ReflectionPlane] {
        self.gaussians.scene().planes()
    }

    /// The exposure the loss applies to training view `view` (the identity when compensation is
    /// off or the view has not been trained on).
    pub fn exposure(&self, view: &str) -> trgs_core::pipeline::ExposureMatrix {
        self.exposures.matrix(view)
    }

    /// The options a render of the current state uses (the SH degree of the last step included).
    pub fn render_options(&self) -> RenderOptions {
        RenderOptions {
            background: self.settings.background,
            sh_degree: Some(self.settings.active_sh_degree(self.step)),
            reflection: self.settings.reflection,
            ..RenderOptions::default()
        }
    }

    /// Render `camera` with the current state (what evaluation and the outputs see).
    pub fn render(&self, camera: &Camera) -> Result<Frame> {
        let options = self.render_options();
        self.renderer.render(self.scene(), camera, &options).context("rendering a view")
    }
}

/// PSNR for data range 1 (infinite for a perfect match).
pub fn psnr_of(mse: f64) -> f64 {
    if mse > 0.0 { -10.0 * mse.log10() } else { f64::INFINITY }
}
