//! The training step itself, in two halves: [`Trainer::record_step`] records and submits the
//! render, losses, guard, backward and Adam without waiting for the GPU, and
//! [`Trainer::finish_step`] reads what came back (loss, guard, key totals, plane gradients) and
//! steps the planes. [`Trainer::train_step`] does both, then the maintenance; a pipelined loop
//! finishes step N after recording step N + 1, so that the GPU always has the next step queued.
use super::phase_clock::PhaseClock;
use super::{StepStats, StepTimes, Trainer, psnr_of};
use crate::data::View;
use crate::densify::{DensifyEvent, StepView};
use crate::exposure::stage::PendingExposureGrad;
use crate::losses::{LossLayers, LossSettings, PendingLoss};
use crate::settings::Stage;
use anyhow::{Context, Result};
use trgs_core::pipeline::{GUARD_KEYS_DROPPED, GUARD_LOSS_NOT_FINITE, RegulariserWeights};
use trgs_core::scene::Attribute;
use trgs_render::PlaneGradsRead;
use trgs_render::toolkit::gpu::{self, PendingRead, Recorder};
use trgs_render::{
    BackwardOptions, Gradients, KeySizing, KeyTotals, LayerGrads, PendingKeyTotals, RenderOptions,
};

/// A step recorded and submitted ([`Trainer::record_step`]) whose results are on their way
/// back; [`Trainer::finish_step`] reads them.
#[derive(Debug)]
#[must_use = "a step's loss and plane gradients are applied when it is finished"]
pub struct StepInFlight {
    /// The step's number, from 1.
    step: u32,
    view: String,
    /// The guard word (16 bytes), the loss strips' sums, then the exposure's (when on).
    readback: PendingRead,
    loss: PendingLoss,
    exposure: Option<PendingExposureGrad>,
    keys: StepKeys,
    planes: PlaneGradsRead,
    times: StepTimes,
    gpu_stages: Vec<(&'static str, f64)>,
    /// Waits for the GPU while it was recorded.
    record_waits: u64,
}

/// Milliseconds of each GPU stage of a phase, with `--profile`.
type StageTimes = Vec<(&'static str, f64)>;

/// What phase loss leaves in flight: the loss, the exposure's gradient sums (when on), their
/// readback (guard word, loss sums, exposure sums) and the phase's stage times.
type RecordedLoss = (PendingLoss, Option<PendingExposureGrad>, PendingRead, StageTimes);

/// The key totals of a step's frame: known when it was sized exactly, else on their way back.
#[derive(Debug)]
enum StepKeys {
    Known(Option<KeyTotals>),
    Pending(PendingKeyTotals),
}

impl StepInFlight {
    /// The step's number, counted from 1.
    pub fn step(&self) -> u32 {
        self.step
    }
}

impl Trainer {
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
    ///
    /// A step whose frame outgrew its key list (sized from earlier frames) changed nothing; it
    /// is taken again with the list sized exactly, so that every step here trains.
    /// A GPU failure (out of memory, a lost device) ends the step with an error, not a panic.
    pub fn train_step_then(
        &mut self,
        view: &View,
        before_maintenance: impl FnOnce(&Trainer) -> Result<()>,
    ) -> Result<StepStats> {
        let ctx = self.ctx.clone();
        gpu::scoped(&ctx, "a training step", || {
            let mut stats = loop {
                let in_flight = self.record_step_scoped(view)?;
                let stats = self.finish_step_scoped(in_flight)?;
                if !stats.skipped {
                    break stats;
                }
                // Nothing changed; finishing it sized the next frame exactly.
                self.step -= 1;
            };
            before_maintenance(self)?;
            let clock = PhaseClock::start(self.waits_between_phases());
            // Taken whole: what the maintenance decides is applied now.
            (stats.densified, stats.perturbed) = self.maintain_scoped(false)?;
            stats.times.densify = clock.elapsed(&self.ctx)?;
            Ok(stats)
        })
    }

    /// Record and submit step `self.step + 1` on `view` (render, losses, guard, backward, Adam on
    /// the Gaussians), advancing `step`, without waiting for the GPU (unless profiling or timing
    /// phases, on a CPU adapter (`Capabilities::records_while_busy`), or when the frame is sized
    /// exactly: the first step, the first recorded after a step that outgrew its key list is
    /// known, and the step after an edit of the set from outside the maintenance). Call
    /// [`Trainer::maintain`] before the next step is recorded, and [`Trainer::finish_step`]
    /// with what this returns before the step after next is (a pipelined loop finishes it after
    /// recording the next one).
    ///
    /// The step's updates are guarded on the GPU (`step_guard`): if its frame dropped keys or its
    /// loss is not finite, they change nothing, and finishing it says which.
    pub fn record_step(&mut self, view: &View) -> Result<StepInFlight> {
        let ctx = self.ctx.clone();
        gpu::scoped(&ctx, "recording a training step", || self.record_step_scoped(view))
    }

    /// Read back what `in_flight` computed (waiting only for its own GPU work), step the planes
    /// by its gradients, and say what it measured. A step whose frame dropped keys changed
    /// nothing and is returned with `skipped` set; a step whose loss is not finite is an error
    /// (it changed nothing either).
    pub fn finish_step(&mut self, in_flight: StepInFlight) -> Result<StepStats> {
        let ctx = self.ctx.clone();
        gpu::scoped(&ctx, "finishing a training step", || self.finish_step_scoped(in_flight))
    }

    /// The densification strategy's maintenance and the opacity perturbation after step
    /// `self.step`, when their schedules run them, for a pipelined loop: it waits for nothing.
    /// A densification or relocation decided now on the GPU is applied at the next call, when
    /// its counters have come back (the GPU runs the next step meanwhile: that step trains the
    /// set as it was), and the perturbation's count is reported then too. Returns what was
    /// applied (the strategy's events) and how many Gaussians were perturbed, as they come
    /// back. After a change of the set, the next frames' key lists expect the keys' growth the
    /// change reports ([`trgs_render::Frame::expect_set_scaled`]) rather than being sized
    /// exactly, which would wait. [`Trainer::settle`] applies what is pending at once.
    pub fn maintain(&mut self) -> Result<(Vec<DensifyEvent>, usize)> {
        let ctx = self.ctx.clone();
        gpu::scoped(&ctx, "densifying", || self.maintain_scoped(true))
    }

    /// Apply what the last [`Trainer::maintain`] left pending (waiting only for its counters):
    /// what it did, and how many Gaussians the perturbation changed (with what an edit of the
    /// set applied since the last report, [`Trainer::edit_gaussians`]).
    pub fn settle(&mut self) -> Result<(Vec<DensifyEvent>, usize)> {
        let ctx = self.ctx.clone();
        gpu::scoped(&ctx, "densifying", || self.settle_scoped())
    }

    /// [`Trainer::settle`] on the way of an edit from outside the maintenance: what it applies
    /// waits for the next report.
    pub(super) fn settle_unreported(&mut self) -> Result<()> {
        let ctx = self.ctx.clone();
        gpu::scoped(&ctx, "densifying", || self.settle_into_unreported())
    }

    /// Whether nothing [`Trainer::maintain`] decided waits: neither a change of the set nor
    /// the perturbation's count. What an edit applied on its way may still wait to be
    /// reported: [`Trainer::settle`] returns it either way.
    pub fn is_settled(&self) -> bool {
        !self.densification.pending() && self.pending_perturbed.is_none()
    }

    /// Whether each phase of a step waits for the GPU before its lap is taken: to time it, or
    /// where recording the next phase would only slow the device down (a CPU adapter,
    /// `Capabilities::records_while_busy`).
    fn waits_between_phases(&self) -> bool {
        self.profile || self.time_phases || !self.ctx.capabilities.records_while_busy
    }

    /// Records and submits the step's phases, each ending with a lap of the step's clock:
    /// render, losses (with the guard and the readback), backward, update.
    fn record_step_scoped(&mut self, view: &View) -> Result<StepInFlight> {
        let waits = self.ctx.waits();
        let stage = self.settings.stage(self.step);
        let mut times = StepTimes::default();
        let mut clock = PhaseClock::start(self.waits_between_phases());
        let keys = self.record_render(view)?;
        times.render = clock.lap(&self.ctx)?;
        let (loss, exposure, readback, loss_stages) = self.record_loss(view)?;
        times.loss = clock.lap(&self.ctx)?;
        let mut grads = self.record_backward(stage)?;
        times.backward = clock.lap(&self.ctx)?;
        let adam_stages = self.record_update(stage, &grads)?;
        times.adam = clock.lap(&self.ctx)?;
        let gpu_stages: Vec<_> = [
            self.frame.stage_times(),
            Some(&loss_stages[..]),
            grads.stage_times(),
            Some(&adam_stages[..]),
        ]
        .into_iter()
        .flatten()
        .flatten()
        .copied()
        .collect();
        Ok(StepInFlight {
            step: self.step,
            view: view.camera.name.clone(),
            readback,
            loss,
            exposure,
            keys,
            planes: std::mem::take(&mut grads.planes),
            times,
            gpu_stages,
            record_waits: self.ctx.waits() - waits,
        })
    }

    /// The step's render options: the degree the model has after it, the depth variance where
    /// a plane needs it, and the key list's sizing.
    fn step_render_options(&mut self) -> RenderOptions {
        let mut options = self.render_options();
        // This step, numbered self.step + 1 from 1, trains the degree the model has after it.
        options.sh_degree = Some(self.settings.active_sh_degree(self.step + 1));
        options.depth_variance = !self.planes().is_empty() && self.settings.lambda_depth > 0.0;
        options.profile = self.profile;
        // The key list is sized from earlier steps' frames, so the render does not wait for its
        // binning; the guard keeps a frame that outgrew it from changing anything.
        options.key_sizing = if std::mem::take(&mut self.exact_keys_next) {
            KeySizing::Exact
        } else {
            KeySizing::FromEarlierFrames
        };
        options
    }

    /// Phase render: the frame of `view`, and its key totals (known, or on their way back).
    fn record_render(&mut self, view: &View) -> Result<StepKeys> {
        let options = self.step_render_options();
        let scene = self.gaussians.scene();
        self.renderer.render_into(scene, &view.camera, &options, &mut self.frame)?;
        Ok(match self.frame.take_pending_keys() {
            Some(p) => StepKeys::Pending(p),
            // Sized exactly: known now, without waiting.
            None => StepKeys::Known(self.frame.settle_keys(&self.ctx)?),
        })
    }

    /// Phase loss: the losses against `view`'s photo into the layer gradients (through the
    /// view's exposure, when compensation is on), the guard word from the loss sums and the
    /// frame's key overflow, and their readback, submitted.
    fn record_loss(&mut self, view: &View) -> Result<RecordedLoss> {
        let ctx = &self.ctx;
        let target = self
            .targets
            .get(ctx, view)
            .with_context(|| format!("uploading view {}", view.camera.name))?;
        let shape = (self.frame.width(), self.frame.height(), self.frame.plane_slots());
        if self.layer_grads.as_ref().is_none_or(|(s, _)| *s != shape) {
            self.layer_grads = Some((shape, LayerGrads::zeros(ctx, &self.frame)?));
        }
        #[allow(clippy::expect_used)]
        let layer_grads = &self.layer_grads.as_ref().expect("allocated above").1;
        let s = &self.settings;
        let loss_settings = LossSettings {
            lambda_dssim: s.lambda_dssim,
            regularisers: (!self.gaussians.scene().planes().is_empty()).then_some(
                RegulariserWeights {
                    depth: s.lambda_depth,
                    conflict: s.lambda_conflict,
                    mask: s.lambda_mask,
                },
            ),
        };
        let mut rec = Recorder::new(ctx, "trgs.train.loss", self.profile);
        let mut layers = LossLayers::of_frame(&self.frame)?;
        let size = (layers.width, layers.height);
        let rendered = layers.color.clone();
        let exposure = self.exposure_kernels.as_mut().map(|kernels| {
            let m = self.exposures.matrix(&view.camera.name);
            (kernels.record_exposure(ctx, &mut rec, &rendered, size, &m), m)
        });
        if let Some((exposed, _)) = &exposure {
            layers.color = exposed;
        }
        let loss = self
            .losses
            .record(ctx, &mut rec, &layers, target, layer_grads, &loss_settings)
            .with_context(|| format!("loss of view {}", view.camera.name))?;
        let exposure = match (exposure, self.exposure_kernels.as_mut()) {
            (Some((_, m)), Some(kernels)) => Some(kernels.record_exposure_bwd(
                ctx,
                &mut rec,
                &rendered,
                &layer_grads.color,
                size,
                &m,
            )),
            _ => None,
        };
        #[allow(clippy::expect_used)]
        let kept = self.frame.key_overflow_flag().expect("the frame was rendered above");
        let (sums, vec4s) = (loss.partials(), loss.partial_vec4s());
        self.guard.record(ctx, &mut rec, sums, vec4s, kept);
        let exposure_vec4s = exposure.as_ref().map_or(0, PendingExposureGrad::vec4s);
        let bytes = 16 + u64::from(vec4s + exposure_vec4s) * 16;
        let staging = gpu::staging(ctx, "trgs.train.step_readback", bytes);
        rec.encoder.copy_buffer_to_buffer(self.guard.word(), 0, &staging, 0, 16);
        rec.encoder.copy_buffer_to_buffer(sums, 0, &staging, 16, u64::from(vec4s) * 16);
        if let Some(e) = &exposure {
            let at = 16 + u64::from(vec4s) * 16;
            rec.encoder.copy_buffer_to_buffer(e.partials(), 0, &staging, at, bytes - at);
        }
        let submission = rec.submit(ctx)?;
        let readback = PendingRead::after(staging, submission);
        Ok((loss, exposure, readback, rec.stage_times().unwrap_or_default()))
    }

    /// Phase backward: every gradient from the layer gradients the losses wrote; in stage 2 the
    /// reflection's gradient does not reach the Gaussians.
    fn record_backward(&mut self, stage: Stage) -> Result<Gradients> {
        let backward = BackwardOptions {
            block_reflection_to_gaussians: stage == Stage::PlaneAdjustment,
            profile: self.profile,
        };
        #[allow(clippy::expect_used)]
        let layer_grads = &self.layer_grads.as_ref().expect("allocated by the loss").1;
        let scene = self.gaussians.scene();
        Ok(self.renderer.backward(scene, &mut self.frame, layer_grads, &backward)?)
    }

    /// Phase update: the step is counted, then Adam steps every attribute between the
    /// strategy's hooks, all behind the guard word; submitted.
    fn record_update(&mut self, stage: Stage, g: &Gradients) -> Result<StageTimes> {
        self.step += 1;
        let (ctx, t, scene) = (&self.ctx, self.step, self.gaussians.scene());
        let rates = self.settings.rates.attribute_rates(
            t - 1,
            self.settings.iterations,
            self.extent,
            scene.sh_coeffs(),
        );
        let guard = self.guard.word();
        let step_view = StepView {
            ctx,
            scene,
            frame: &self.frame,
            grads: g,
            step: t,
            stage,
            rates: &rates,
            seed: self.settings.seed,
            guard,
        };
        let mut rec = Recorder::new(ctx, "trgs.train.adam", self.profile);
        self.densification.record_before_adam(&step_view, &mut rec);
        let moments = self.gaussians.moments();
        for a in Attribute::ALL {
            let (values, grads) = (scene.parameter(a), g.gaussians.parameter(a));
            self.adam.record(ctx, &mut rec, values, grads, &moments[a], &rates[a], t, guard);
        }
        self.densification.record_after_adam(&step_view, &mut rec);
        rec.submit(ctx)?;
        Ok(rec.stage_times().unwrap_or_default())
    }

    fn finish_step_scoped(&mut self, in_flight: StepInFlight) -> Result<StepStats> {
        let ctx = &self.ctx.clone();
        let clock = PhaseClock::start(false);
        let StepInFlight {
            step,
            view,
            readback,
            loss,
            exposure,
            keys,
            planes,
            mut times,
            gpu_stages,
            record_waits,
        } = in_flight;
        let (loss_vec4s, exposure_vec4s) =
            (loss.partial_vec4s() as usize, exposure.as_ref().map_or(0, |e| e.vec4s() as usize));
        let words: Vec<u32> = readback.read(ctx, 16 * (1 + loss_vec4s + exposure_vec4s))?;
        let guard = words[0];
        let loss_words = &words[4..4 + 4 * loss_vec4s];
        let values = loss.values_of(bytemuck::cast_slice(loss_words));
        let keys = match keys {
            StepKeys::Pending(p) => Some(self.frame.settle_pending_keys(ctx, p)?),
            StepKeys::Known(k) => k,
        };
        if guard & GUARD_LOSS_NOT_FINITE != 0 || !values.value.is_finite() {
            anyhow::bail!("loss of view {view}: not finite ({})", values.value);
        }
        let skipped = guard & GUARD_KEYS_DROPPED != 0;
        let planes = planes.read(ctx)?;
        if skipped {
            // The next frame recorded is sized exactly: a list sized from earlier frames is
            // capped at two pages, and a frame over them must be refused by name, not skipped
            // again and again.
            self.exact_keys_next = true;
        } else {
            self.step_planes(&planes, step)?;
            if let (Some(e), Some(rates)) = (&exposure, self.settings.exposure) {
                let grad = e.gradient_of(bytemuck::cast_slice(&words[4 + 4 * loss_vec4s..]));
                let lr = rates.at(step - 1, self.settings.iterations);
                self.exposures.step(&view, &grad, lr);
            }
        }
        times.readback = clock.elapsed(ctx)?;
        Ok(StepStats {
            step,
            loss: values.value,
            l1: values.l1,
            ssim: values.ssim,
            psnr: psnr_of(values.mse),
            keys: keys.map_or(0, |k| k.keys),
            skipped,
            record_waits,
            times,
            gpu_stages,
            densified: Vec::new(),
            perturbed: 0,
        })
    }

    /// The maintenance after step `self.step`; with `defer`, a change of the set decided now is
    /// left pending, else applied before the perturbation (which then sees the new set, as it
    /// would have without the deferral).
    fn maintain_scoped(&mut self, defer: bool) -> Result<(Vec<DensifyEvent>, usize)> {
        // What is applied goes to `unreported` as it is, so that an error on the way loses
        // none of it: the next report still says what changed the set.
        self.settle_into_unreported()?;
        let (t, n) = (self.step, self.gaussians.len());
        let done =
            self.densification.maintain(t, &mut self.gaussians, &mut self.rng, self.extent)?;
        self.after_change(&done, n);
        self.unreported.0.extend(done);
        if !defer {
            let events = self.settle_set()?;
            self.unreported.0.extend(events);
        }
        self.pending_perturbed = self.perturb_step()?;
        if !defer {
            self.unreported.1 += self.take_perturbed()?;
        }
        Ok(std::mem::take(&mut self.unreported))
    }

    /// Apply the change of the set and read the perturbation's count left pending: what they
    /// did, after what an edit applied since the last report.
    pub(super) fn settle_scoped(&mut self) -> Result<(Vec<DensifyEvent>, usize)> {
        self.settle_into_unreported()?;
        Ok(std::mem::take(&mut self.unreported))
    }

    /// Apply the change of the set and read the perturbation's count left pending, into
    /// `unreported`.
    fn settle_into_unreported(&mut self) -> Result<()> {
        let events = self.settle_set()?;
        self.unreported.0.extend(events);
        self.unreported.1 += self.take_perturbed()?;
        Ok(())
    }

    /// Apply the change of the set the strategy left pending, if any.
    fn settle_set(&mut self) -> Result<Vec<DensifyEvent>> {
        let n = self.gaussians.len();
        let events = self.densification.settle(&mut self.gaussians)?;
        self.after_change(&events, n);
        Ok(events)
    }

    /// The count of the perturbation left pending (0 when none).
    fn take_perturbed(&mut self) -> Result<usize> {
        match self.pending_perturbed.take() {
            Some(read) => Ok(crate::planes::perturb::read_count(&self.ctx, read)?),
            None => Ok(0),
        }
    }

    /// After `events` changed a set of `n` Gaussians: the next frame's key list expects their
    /// growth (an opacity reset changes no Gaussian's footprint: nothing then).
    fn after_change(&mut self, events: &[DensifyEvent], n: usize) {
        for e in events {
            let growth = match e {
                DensifyEvent::Densified(r) => r.key_growth(),
                DensifyEvent::Relocated(r) => r.key_growth(n),
                DensifyEvent::OpacityReset => continue,
            };
            self.frame.expect_set_scaled(growth);
        }
    }
}
