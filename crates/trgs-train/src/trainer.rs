//! One training step on the GPU: render the view, the image loss and its gradient, the backward
//! pass, then Adam on every attribute buffer in place (the Gaussians never leave the GPU) and on
//! the planes (a few numbers each, on the CPU).
use crate::adam::{Adam, AdamMoments};
use crate::checkpoint::{Checkpoint, PlaneMoments};
use crate::data::View;
use crate::densify::{ClassicSettings, DensifyReport, TrainState, cap_opacity_logits};
use crate::densify_stats::GpuDensifyStats;
use crate::gather_rows::GpuRowGather;
use crate::losses::{GpuTarget, LossKernels, LossLayers, LossSettings};
use crate::mcmc::{McmcKernels, McmcSettings};
use crate::perturb::{perturb_opacities, seen_through_planes};
use crate::plane_adam::{PlaneRates, plane_adam};
use crate::settings::{Stage, TrainSettings};

mod phase_clock;
mod rebuild;
use anyhow::{Context, Result};
use phase_clock::PhaseClock;
use std::collections::HashMap;
use trgs_core::reference::{AdamSettings, RegulariserWeights};
use trgs_core::scene::{
    Attribute, Camera, Gaussians, PerAttribute, ReflectionPlane, attribute_widths,
};
use trgs_render::gpu::Recorder;
use trgs_render::{
    BackwardOptions, Frame, GpuContext, GpuScene, LayerGrads, RenderOptions, Renderer,
};

/// What one step measured.
#[derive(Clone, Debug, PartialEq)]
pub struct StepStats {
    pub loss: f64,
    pub l1: f64,
    pub ssim: f64,
    /// PSNR of the rendered training view.
    pub psnr: f64,
    /// Where the step's wall-clock time went.
    pub times: StepTimes,
    /// With [`Trainer::profile`]: GPU milliseconds of every render and backward stage, from
    /// timestamp queries (empty when off or when the adapter has none).
    pub gpu_stages: Vec<(&'static str, f64)>,
    /// Gaussians whose opacity the perturbation changed after this step (0 on most steps).
    pub perturbed: usize,
}

/// Wall-clock milliseconds of each phase of a step. Every phase ends with the GPU idle (the
/// step reads back between phases anyway), so the phases add up to the step.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StepTimes {
    /// Forward render of every pass.
    pub render: f64,
    /// The image loss and the regularisers (GPU), and the readback of their values.
    pub loss: f64,
    /// The adjoint passes and the plane-gradient readback.
    pub backward: f64,
    /// Adam on the Gaussians (GPU) and the planes (CPU), and the densification statistics.
    pub adam: f64,
    /// Densification, pruning, opacity reset and perturbation, when their schedules run them.
    pub densify: f64,
}

impl StepTimes {
    pub fn total(&self) -> f64 {
        self.render + self.loss + self.backward + self.adam + self.densify
    }

    /// The phases as (name, ms) pairs, for logs and reports.
    pub fn phases(&self) -> [(&'static str, f64); 5] {
        [
            ("render", self.render),
            ("loss", self.loss),
            ("backward", self.backward),
            ("adam", self.adam),
            ("densify", self.densify),
        ]
    }

    /// Add `other` phase by phase (for averages over a run).
    pub fn accumulate(&mut self, other: &StepTimes) {
        self.render += other.render;
        self.loss += other.loss;
        self.backward += other.backward;
        self.adam += other.adam;
        self.densify += other.densify;
    }
}

/// The optimisation state on the GPU.
#[derive(Debug)]
pub struct Trainer {
    ctx: GpuContext,
    renderer: Renderer,
    scene: GpuScene,
    adam: Adam,
    moments: PerAttribute<AdamMoments>,
    plane_moments: Vec<PlaneMoments>,
    frame: Frame,
    losses: LossKernels,
    /// Every training view's image and glass labels, uploaded on first use.
    targets: HashMap<String, GpuTarget>,
    /// dL/d(layer) buffers, reused while the frame size and plane count stay.
    layer_grads: Option<((u32, u32, usize), LayerGrads)>,
    /// Steps taken so far.
    pub step: u32,
    pub settings: TrainSettings,
    /// The scene extent (scales the position and plane-centre rates).
    pub extent: f64,
    /// Classic densification, when on, and its statistics since the last densification.
    densify: Option<(ClassicSettings, GpuDensifyStats)>,
    /// MCMC densification, when on (instead of classic), with its GPU stages.
    mcmc: Option<(McmcSettings, McmcKernels)>,
    /// Rebuilds the Gaussians after a densification or relocation on the GPU.
    gather: GpuRowGather,
    rng: trgs_core::rng::Rng,
    /// Time every GPU stage of each step with timestamp queries ([`StepStats::gpu_stages`]).
    pub profile: bool,
    /// Centres of the training cameras (the opacity perturbation selects what they see through
    /// a plane).
    camera_centres: Vec<glam::DVec3>,
}

impl Trainer {
    /// Upload `gaussians` and `planes` and start from zero moments.
    pub fn new(
        ctx: &GpuContext,
        gaussians: &Gaussians<f32>,
        planes: &[ReflectionPlane],
        settings: TrainSettings,
        extent: f64,
    ) -> Result<Self> {
        trgs_render::gpu::scoped(ctx, "setting up training", || {
            Self::new_scoped(ctx, gaussians, planes, settings, extent)
        })
    }

    fn new_scoped(
        ctx: &GpuContext,
        gaussians: &Gaussians<f32>,
        planes: &[ReflectionPlane],
        settings: TrainSettings,
        extent: f64,
    ) -> Result<Self> {
        let scene = GpuScene::upload(ctx, gaussians, planes).context("uploading the Gaussians")?;
        let moments = zero_moments(ctx, &scene);
        Ok(Self {
            ctx: ctx.clone(),
            renderer: Renderer::new(ctx),
            adam: Adam::new(ctx, AdamSettings::default()),
            moments,
            plane_moments: vec![PlaneMoments::default(); planes.len()],
            scene,
            frame: Frame::default(),
            losses: LossKernels::new(ctx),
            targets: HashMap::new(),
            layer_grads: None,
            step: 0,
            rng: trgs_core::rng::Rng::new(settings.seed ^ 0x5eed),
            settings,
            extent,
            densify: None,
            mcmc: None,
            gather: GpuRowGather::new(ctx),
            profile: false,
            camera_centres: Vec::new(),
        })
    }

    /// Continue from `ck` (written by [`Trainer::checkpoint`]) with `settings`, which should be
    /// those of the interrupted run; densification as it was then, with `densify`'s schedule.
    pub fn from_checkpoint(
        ctx: &GpuContext,
        ck: &Checkpoint,
        settings: TrainSettings,
        extent: f64,
        densify: Option<ClassicSettings>,
    ) -> Result<Self> {
        trgs_render::gpu::scoped(ctx, "resuming from a checkpoint", || {
            Self::resume_scoped(ctx, ck, settings, extent, densify)
        })
    }

    fn resume_scoped(
        ctx: &GpuContext,
        ck: &Checkpoint,
        settings: TrainSettings,
        extent: f64,
        densify: Option<ClassicSettings>,
    ) -> Result<Self> {
        let mut t = Self::new(ctx, &ck.state.gaussians, &ck.planes, settings, extent)?;
        t.set_state(&ck.state)?;
        t.plane_moments = ck.plane_moments.clone();
        t.step = ck.step;
        t.rng = trgs_core::rng::Rng::from_state(ck.rng_state);
        if let Some(d) = densify {
            let n = ck.state.gaussians.len();
            let stats = match &ck.densify_stats {
                Some(s) => GpuDensifyStats::from_stats(ctx, s),
                None => GpuDensifyStats::new(ctx, n),
            };
            t.densify = Some((d, stats));
        }
        Ok(t)
    }

    /// Everything needed to continue this run later, with `extra` for the caller's own state.
    pub fn checkpoint(&self, extra: serde_json::Value) -> Result<Checkpoint> {
        Ok(Checkpoint {
            step: self.step,
            state: self.read_state()?,
            planes: self.scene.planes().to_vec(),
            plane_moments: self.plane_moments.clone(),
            densify_stats: self.densify.as_ref().map(|(_, s)| s.read(&self.ctx)).transpose()?,
            rng_state: self.rng.state(),
            extra,
        })
    }

    /// The training cameras (for the opacity perturbation; without them it perturbs nothing).
    pub fn set_training_cameras(&mut self, cameras: &[Camera]) {
        self.camera_centres = cameras.iter().map(|c| c.pose.centre()).collect();
    }

    /// Opacity perturbation after step `self.step`, when its schedule says so; returns how many
    /// Gaussians it perturbed.
    fn perturb_step(&mut self) -> Result<usize> {
        let t = self.step;
        let Some(p) = self.settings.perturb else { return Ok(0) };
        let reset_now = self.densify.as_ref().is_some_and(|(s, _)| s.resets_opacity_at(t));
        if self.scene.planes().is_empty()
            || self.settings.stage(t) != Stage::Joint
            || t >= p.until
            || !t.is_multiple_of(p.every)
            || reset_now
        {
            return Ok(0);
        }
        let mut g = self.gaussians()?;
        let selected = seen_through_planes(&g, self.scene.planes(), &self.camera_centres);
        let n = perturb_opacities(&mut g, &selected, p.amplitude, &mut self.rng);
        // Only the opacity buffer changes: the moments and densification statistics stay.
        self.write_opacity_logits(&g.opacity_logits);
        Ok(n)
    }

    /// Densify with `settings` from now on.
    pub fn enable_densification(&mut self, settings: ClassicSettings) {
        let stats = GpuDensifyStats::new(&self.ctx, self.scene.len() as usize);
        self.densify = Some((settings, stats));
    }

    /// Densify with MCMC (relocation, growth up to the cap, noise, regularisers) from now on,
    /// instead of classic densification.
    pub fn enable_mcmc(&mut self, settings: McmcSettings) {
        self.densify = None;
        let kernels = McmcKernels::new(&self.ctx);
        self.mcmc = Some((settings, kernels));
    }

    /// The parameters and Adam moments, read back.
    pub fn read_state(&self) -> Result<TrainState> {
        let read = |b: &wgpu::Buffer, len: u64| {
            trgs_render::gpu::read_buffer::<f32>(&self.ctx, b, 0, len as usize)
        };
        let (mut m, mut v) = (PerAttribute::default(), PerAttribute::default());
        for (a, mo) in self.moments.iter() {
            m[a] = read(&mo.m, mo.len)?;
            v[a] = read(&mo.v, mo.len)?;
        }
        Ok(TrainState { gaussians: self.gaussians()?, m, v })
    }

    /// Replace the parameters and moments (after an edit such as densification).
    pub fn set_state(&mut self, state: &TrainState) -> Result<()> {
        let ctx = self.ctx.clone();
        trgs_render::gpu::scoped(&ctx, "uploading the training state", || {
            self.set_state_scoped(state)
        })
    }

    fn set_state_scoped(&mut self, state: &TrainState) -> Result<()> {
        let planes = self.scene.planes().to_vec();
        self.scene = GpuScene::upload(&self.ctx, &state.gaussians, &planes)
            .context("uploading the edited Gaussians")?;
        self.moments = PerAttribute::from_fn(|a| {
            AdamMoments::from_values(&self.ctx, a.name(), &state.m[a], &state.v[a])
        });
        if let Some((_, stats)) = &mut self.densify {
            stats.reset(&self.ctx, state.gaussians.len());
        }
        Ok(())
    }

    /// Replace the opacity logits on the GPU (the other parameters and all moments stay).
    fn write_opacity_logits(&self, logits: &[f32]) {
        let opacity = self.scene.parameter(Attribute::OpacityLogits);
        self.ctx.queue.write_buffer(opacity, 0, bytemuck::cast_slice(logits));
    }

    /// Densification after step `self.step`, when the schedule says so.
    fn densify_step(&mut self) -> Result<Option<DensifyReport>> {
        if let Some((settings, _)) = &self.mcmc {
            if settings.relocates_at(self.step) {
                self.relocate_now()?;
            }
            return Ok(None);
        }
        let Some((settings, _)) = &self.densify else { return Ok(None) };
        let t = self.step;
        let mut report = None;
        if t > settings.from && t < settings.until && t.is_multiple_of(settings.every) {
            let prune_large = t > settings.opacity_reset_every;
            report = Some(self.densify_now(prune_large)?);
        }
        let reset = self.densify.as_ref().is_some_and(|(s, _)| s.resets_opacity_at(t));
        if reset {
            // In place: only the opacities and their moments change, so the densification
            // statistics gathered since the last densification stay (rebuilding the state, as
            // a densification does, used to clear them).
            let opacity = self.scene.parameter(Attribute::OpacityLogits);
            let mut logits: Vec<f32> =
                trgs_render::gpu::read_buffer(&self.ctx, opacity, 0, self.scene.len() as usize)?;
            cap_opacity_logits(&mut logits);
            self.write_opacity_logits(&logits);
            let mut enc = self.ctx.device.create_command_encoder(&Default::default());
            let moments = &self.moments[Attribute::OpacityLogits];
            enc.clear_buffer(&moments.m, 0, None);
            enc.clear_buffer(&moments.v, 0, None);
            self.ctx.queue.submit([enc.finish()]);
        }
        Ok(report)
    }

    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    pub fn renderer(&self) -> &Renderer {
        &self.renderer
    }

    pub fn scene(&self) -> &GpuScene {
        &self.scene
    }

    /// The current Gaussians, read back from the GPU.
    pub fn gaussians(&self) -> Result<Gaussians<f32>> {
        Ok(self.scene.read(&self.ctx)?)
    }

    pub fn planes(&self) -> &[ReflectionPlane] {
        self.scene.planes()
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

    /// Render `camera` with the current parameters.
    pub fn render(&self, camera: &Camera) -> Result<Frame> {
        Ok(self.renderer.render(&self.scene, camera, &self.render_options())?)
    }

    /// One optimisation step on `view`.
    pub fn train_step(&mut self, view: &View) -> Result<StepStats> {
        self.train_step_then(view, |_| Ok(()))
    }

    /// One optimisation step on `view`, calling `before_maintenance` with the updated parameters
    /// (and `step` already advanced) before the step's densification, opacity reset and
    /// perturbation, as 3DGS reports its test views there: an evaluation then measures the
    /// model the step made, not the moment an opacity reset or perturbation knocked it back
    /// (the training recovers from those within a few steps). Its time is not in the step's
    /// phase times.
    /// A GPU failure (out of memory, a lost device) ends the step with an error, not a panic.
    pub fn train_step_then(
        &mut self,
        view: &View,
        before_maintenance: impl FnOnce(&Trainer) -> Result<()>,
    ) -> Result<StepStats> {
        let ctx = self.ctx.clone();
        trgs_render::gpu::scoped(&ctx, "a training step", || {
            self.train_step_scoped(view, before_maintenance)
        })
    }

    fn train_step_scoped(
        &mut self,
        view: &View,
        before_maintenance: impl FnOnce(&Trainer) -> Result<()>,
    ) -> Result<StepStats> {
        let ctx = &self.ctx;
        let stage = self.settings.stage(self.step);
        let has_planes = !self.scene.planes().is_empty();
        let mut options = self.render_options();
        // This step, numbered self.step + 1 from 1, trains the degree the model has after it.
        options.sh_degree = Some(self.settings.active_sh_degree(self.step + 1));
        options.depth_variance = has_planes && self.settings.lambda_depth > 0.0;
        options.profile = self.profile;
        let mut times = StepTimes::default();
        let mut clock = PhaseClock::start();
        self.renderer.render_into(&self.scene, &view.camera, &options, &mut self.frame)?;
        times.render = clock.lap(&self.ctx)?;
        let target = match self.targets.entry(view.camera.name.clone()) {
            std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
            std::collections::hash_map::Entry::Vacant(e) => e.insert(GpuTarget::upload(
                ctx,
                &view.camera.name,
                &view.image,
                view.mask.as_ref(),
            )?),
        };
        let shape = (self.frame.width(), self.frame.height(), self.frame.plane_slots());
        if self.layer_grads.as_ref().is_none_or(|(s, _)| *s != shape) {
            self.layer_grads = Some((shape, LayerGrads::zeros(ctx, &self.frame)?));
        }
        #[allow(clippy::expect_used)]
        let layer_grads = &self.layer_grads.as_ref().expect("allocated above").1;
        let s = &self.settings;
        let loss_settings = LossSettings {
            lambda_dssim: s.lambda_dssim,
            regularisers: has_planes.then_some(RegulariserWeights {
                depth: s.lambda_depth,
                conflict: s.lambda_conflict,
                mask: s.lambda_mask,
            }),
        };
        let mut rec = Recorder::new(ctx, "trgs.train.loss", self.profile);
        let pending = self
            .losses
            .record(
                ctx,
                &mut rec,
                &LossLayers::of_frame(&self.frame)?,
                target,
                layer_grads,
                &loss_settings,
            )
            .with_context(|| format!("loss of view {}", view.camera.name))?;
        rec.submit_and_wait(ctx)?;
        let loss = pending.read(ctx)?;
        if !loss.value.is_finite() {
            anyhow::bail!("loss of view {}: not finite ({})", view.camera.name, loss.value);
        }
        let loss_stages = rec.stage_times().unwrap_or_default();
        times.loss = clock.lap(&self.ctx)?;
        let backward = BackwardOptions {
            block_reflection_to_gaussians: stage == Stage::PlaneAdjustment,
            profile: self.profile,
        };
        let g = self.renderer.backward(&self.scene, &mut self.frame, layer_grads, &backward)?;
        times.backward = clock.lap(&self.ctx)?;
        let gpu_stages: Vec<_> =
            [self.frame.stage_times(), Some(&loss_stages[..]), g.stage_times()]
                .into_iter()
                .flatten()
                .flatten()
                .copied()
                .collect();
        self.step += 1;
        let t = self.step;
        let rates = self.settings.rates.attribute_rates(
            t - 1,
            self.settings.iterations,
            self.extent,
            self.scene.sh_coeffs(),
        );
        let mut rec = Recorder::new(ctx, "trgs.train.adam", false);
        if let Some((settings, kernels)) = &self.mcmc {
            kernels.record_regularise(ctx, &mut rec, &self.scene, &g.gaussians, settings);
        }
        for a in Attribute::ALL {
            let (values, grads) = (self.scene.parameter(a), g.gaussians.parameter(a));
            self.adam.record(ctx, &mut rec, values, grads, &self.moments[a], &rates[a], t);
        }
        if let Some((settings, kernels)) = &self.mcmc {
            // A seed per step (the step survives a resume, so the noise does too).
            let seed = (self.settings.seed as u32).wrapping_mul(0x9e37_79b9) ^ t;
            kernels.record_noise(
                ctx,
                &mut rec,
                &self.scene,
                settings,
                &rates[Attribute::Means],
                seed,
            );
        }
        if let Some((settings, stats)) = &self.densify
            && t <= settings.until
        {
            // The camera's pass, and in the joint stage each plane's mirrored pass too (see
            // `DensifyStats::add`). In stage 2 the reflection's gradient does not reach the
            // Gaussians: its passes hold zeros.
            let views = if stage == Stage::Joint { self.frame.views().len() } else { 1 };
            stats.record_add(ctx, &mut rec, &self.frame, &g, views);
        }
        rec.submit_and_wait(ctx)?;
        self.step_planes(&g.planes, t)?;
        times.adam = clock.lap(&self.ctx)?;
        before_maintenance(self)?;
        clock.lap(&self.ctx)?;
        self.densify_step()?;
        let perturbed = self.perturb_step()?;
        times.densify = clock.lap(&self.ctx)?;
        Ok(StepStats {
            loss: loss.value,
            l1: loss.l1,
            ssim: loss.ssim,
            psnr: psnr_of(loss.mse),
            times,
            gpu_stages,
            perturbed,
        })
    }

    /// Add reflection planes and their glass Gaussians (zero moments) to the optimisation.
    pub fn add_planes(&mut self, planes: &[ReflectionPlane], glass: &Gaussians<f32>) -> Result<()> {
        let mut state = self.read_state()?;
        let n_old = state.gaussians.len();
        let g = &mut state.gaussians;
        g.means.extend_from_slice(&glass.means);
        g.rotations.extend_from_slice(&glass.rotations);
        g.log_scales.extend_from_slice(&glass.log_scales);
        g.opacity_logits.extend_from_slice(&glass.opacity_logits);
        g.sh.extend_from_slice(&glass.with_sh_degree(g.sh_degree).sh);
        g.mask_logits.extend_from_slice(&glass.mask_logits);
        g.log_reflections.extend_from_slice(&glass.log_reflections);
        g.populations.extend_from_slice(&glass.populations);
        let widths = attribute_widths(g.sh_coeffs());
        for a in Attribute::ALL {
            let len = (n_old + glass.len()) * widths[a];
            state.m[a].resize(len, 0.0);
            state.v[a].resize(len, 0.0);
        }
        let mut all = self.scene.planes().to_vec();
        all.extend_from_slice(planes);
        self.scene.set_planes(&all).context("initialised planes")?;
        self.plane_moments.resize(all.len(), PlaneMoments::default());
        self.set_state(&state)
    }

    /// Adam on the planes' offset along the normal, normal and R0 logit ([`plane_adam`]).
    fn step_planes(&mut self, grads: &[trgs_core::reference::PlaneGrad], t: u32) -> Result<()> {
        if grads.is_empty() {
            return Ok(());
        }
        let r = &self.settings.rates;
        // Stage 3 fine-tunes the planes' position and normal at a tenth of the rate.
        let fine =
            if self.settings.stage(t - 1) == Stage::Joint { r.plane_stage3_factor } else { 1.0 };
        let mut planes = self.scene.planes().to_vec();
        let rates = PlaneRates {
            offset: fine * r.plane_centre * self.extent,
            normal: fine * r.plane_normal,
            r0_logit: r.plane_r0,
        };
        let stage1 = self.settings.stage1;
        for ((plane, g), mom) in planes.iter_mut().zip(grads).zip(&mut self.plane_moments) {
            // Adam's bias correction counts the plane's own steps: its moments start at zero
            // when it is created (at the end of stage 1), and with the run's step count instead
            // the first steps would be several times the rate (1 - b2^t near 1 under a tiny v).
            // A checkpoint from before the count started: the planes began after stage 1.
            if mom.steps == 0 && mom.v.iter().any(|&v| v != 0.0) {
                mom.steps = t.saturating_sub(stage1 + 1);
            }
            mom.steps += 1;
            plane_adam(plane, g, mom, &rates, mom.steps);
        }
        self.scene.set_planes(&planes).context("a plane step left an invalid plane")?;
        Ok(())
    }
}

fn zero_moments(ctx: &GpuContext, scene: &GpuScene) -> PerAttribute<AdamMoments> {
    let n = u64::from(scene.len());
    let widths = scene.attribute_widths();
    PerAttribute::from_fn(|a| AdamMoments::zeros(ctx, a.name(), n * u64::from(widths[a])))
}

/// PSNR for data range 1 (infinite for a perfect match).
pub fn psnr_of(mse: f64) -> f64 {
    if mse > 0.0 { -10.0 * mse.log10() } else { f64::INFINITY }
}
