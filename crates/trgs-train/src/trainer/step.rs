//! The training step itself.
use super::phase_clock::PhaseClock;
use super::{StepStats, StepTimes, Trainer, psnr_of};
use crate::data::View;
use crate::densify::StepView;
use crate::losses::{LossLayers, LossSettings};
use crate::settings::Stage;
use anyhow::{Context, Result};
use trgs_core::reference::RegulariserWeights;
use trgs_core::scene::Attribute;
use trgs_render::toolkit::gpu::Recorder;
use trgs_render::{BackwardOptions, KeySizing, LayerGrads};

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
    /// A GPU failure (out of memory, a lost device) ends the step with an error, not a panic.
    pub fn train_step_then(
        &mut self,
        view: &View,
        before_maintenance: impl FnOnce(&Trainer) -> Result<()>,
    ) -> Result<StepStats> {
        let ctx = self.ctx.clone();
        trgs_render::toolkit::gpu::scoped(&ctx, "a training step", || {
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
        let has_planes = !self.planes().is_empty();
        let mut options = self.render_options();
        // This step, numbered self.step + 1 from 1, trains the degree the model has after it.
        options.sh_degree = Some(self.settings.active_sh_degree(self.step + 1));
        options.depth_variance = has_planes && self.settings.lambda_depth > 0.0;
        options.profile = self.profile;
        let mut times = StepTimes::default();
        let mut clock = PhaseClock::start();
        let scene = self.gaussians.scene();
        // The key list is sized from earlier steps' frames, so the render does not wait for its
        // binning; the totals arrive with the loss. A frame that outgrew the list dropped keys:
        // it is rendered again, sized exactly, before anything learns from it.
        options.key_sizing = KeySizing::FromEarlierFrames;
        let (loss, loss_stages) = loop {
            self.renderer.render_into(scene, &view.camera, &options, &mut self.frame)?;
            times.render += clock.lap(&self.ctx)?;
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
            times.loss += clock.lap(&self.ctx)?;
            let totals = self.frame.settle_keys(ctx)?;
            if totals.is_none_or(|t| t.held()) {
                break (loss, rec.stage_times().unwrap_or_default());
            }
            options.key_sizing = KeySizing::Exact;
        };
        let keys = self.frame.key_count();
        if !loss.value.is_finite() {
            anyhow::bail!("loss of view {}: not finite ({})", view.camera.name, loss.value);
        }
        #[allow(clippy::expect_used)]
        let layer_grads = &self.layer_grads.as_ref().expect("allocated with the loss").1;
        let backward = BackwardOptions {
            block_reflection_to_gaussians: stage == Stage::PlaneAdjustment,
            profile: self.profile,
        };
        let g = self.renderer.backward(scene, &mut self.frame, layer_grads, &backward)?;
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
            scene.sh_coeffs(),
        );
        let view = StepView {
            ctx,
            scene,
            frame: &self.frame,
            grads: &g,
            step: t,
            stage,
            rates: &rates,
            seed: self.settings.seed,
        };
        let mut rec = Recorder::new(ctx, "trgs.train.adam", false);
        self.densification.record_before_adam(&view, &mut rec);
        let moments = self.gaussians.moments();
        for a in Attribute::ALL {
            let (values, grads) = (scene.parameter(a), g.gaussians.parameter(a));
            self.adam.record(ctx, &mut rec, values, grads, &moments[a], &rates[a], t);
        }
        self.densification.record_after_adam(&view, &mut rec);
        rec.submit_and_wait(ctx)?;
        self.step_planes(&g.planes, t)?;
        times.adam = clock.lap(&self.ctx)?;
        before_maintenance(self)?;
        clock.lap(&self.ctx)?;
        let densified =
            self.densification.maintain(t, &mut self.gaussians, &mut self.rng, self.extent)?;
        let perturbed = self.perturb_step()?;
        times.densify = clock.lap(&self.ctx)?;
        Ok(StepStats {
            loss: loss.value,
            l1: loss.l1,
            ssim: loss.ssim,
            psnr: psnr_of(loss.mse),
            keys,
            times,
            gpu_stages,
            densified,
            perturbed,
        })
    }
}
