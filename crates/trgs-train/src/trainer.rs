//! One training step on the GPU: render the view, the image loss and its gradient, the backward
//! pass, then Adam on every attribute buffer in place (the Gaussians never leave the GPU) and on
//! the planes (a few numbers each, on the CPU).
use crate::adam::{Adam, AdamMoments};
use crate::data::View;
use crate::settings::TrainSettings;
use anyhow::{Context, Result};
use trgs_core::Image;
use trgs_core::reference::{AdamRate, AdamSettings, FrameGrads, adam, photometric_loss};
use trgs_core::scene::{Camera, Gaussians, ReflectionPlane};
use trgs_render::gpu::Recorder;
use trgs_render::{
    ATTRIBUTES, BackwardOptions, Frame, GpuContext, GpuScene, Layer, LayerGrads, RenderOptions,
    Renderer,
};

/// What one step measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepStats {
    pub loss: f64,
    pub l1: f64,
    pub ssim: f64,
    /// PSNR of the rendered training view.
    pub psnr: f64,
}

/// Adam state of one plane: centre, unnormalised normal, R0 logit.
#[derive(Clone, Debug, Default)]
struct PlaneMoments {
    m: [f64; 7],
    v: [f64; 7],
}

/// The optimisation state on the GPU.
#[derive(Debug)]
pub struct Trainer {
    ctx: GpuContext,
    renderer: Renderer,
    scene: GpuScene,
    adam: Adam,
    moments: Vec<AdamMoments>,
    plane_moments: Vec<PlaneMoments>,
    frame: Frame,
    /// Steps taken so far.
    pub step: u32,
    pub settings: TrainSettings,
    /// The scene extent (scales the position and plane-centre rates).
    pub extent: f64,
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
            step: 0,
            settings,
            extent,
        })
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
    pub fn gaussians(&self) -> Gaussians<f32> {
        self.scene.read(&self.ctx)
    }

    pub fn planes(&self) -> &[ReflectionPlane] {
        self.scene.planes()
    }

    /// The options a render of the current state uses (the active SH degree included).
    pub fn render_options(&self) -> RenderOptions {
        RenderOptions {
            background: self.settings.background,
            sh_degree: Some(self.settings.active_sh_degree(self.step)),
            ..RenderOptions::default()
        }
    }

    /// Render `camera` with the current parameters.
    pub fn render(&self, camera: &Camera) -> Result<Frame> {
        Ok(self.renderer.render(&self.scene, camera, &self.render_options())?)
    }

    /// One optimisation step on `view`.
    pub fn train_step(&mut self, view: &View) -> Result<StepStats> {
        let ctx = &self.ctx;
        let options = self.render_options();
        self.renderer.render_into(&self.scene, &view.camera, &options, &mut self.frame)?;
        let color = self.frame.read_layer(ctx, Layer::Color);
        let loss =
            photometric_loss(&to_f64(&color), &to_f64(&view.image), self.settings.lambda_dssim)
                .with_context(|| format!("loss of view {}", view.camera.name))?;
        let mut grads = FrameGrads::zeros(color.width, color.height, self.scene.planes().len());
        grads.color = loss.grad;
        let layer_grads = LayerGrads::upload(ctx, &self.frame, &grads)?;
        let g = self.renderer.backward(
            &self.scene,
            &mut self.frame,
            &layer_grads,
            &BackwardOptions::default(),
        )?;
        self.step += 1;
        let t = self.step;
        let rates = self.settings.rates.attribute_rates(
            t - 1,
            self.settings.iterations,
            self.extent,
            self.scene.attribute_widths()[4] / 3,
        );
        let mut rec = Recorder::new(ctx, "trgs.train.adam", false);
        let values = self.scene.parameters();
        let grad_buffers = g.gaussians.parameters();
        for k in 0..ATTRIBUTES.len() {
            self.adam.record(
                ctx,
                &mut rec,
                values[k],
                grad_buffers[k],
                &self.moments[k],
                &rates[k],
                t,
            );
        }
        rec.submit_and_wait(ctx);
        self.step_planes(&g.planes, t)?;
        let mse = loss_mse(&color, &view.image);
        Ok(StepStats { loss: loss.value, l1: loss.l1, ssim: loss.ssim, psnr: psnr_of(mse) })
    }

    /// Adam on the planes' centre, normal and R0 logit (on the CPU: seven numbers a plane).
    fn step_planes(&mut self, grads: &[trgs_core::reference::PlaneGrad], t: u32) -> Result<()> {
        if grads.is_empty() {
            return Ok(());
        }
        let r = &self.settings.rates;
        let mut planes = self.scene.planes().to_vec();
        for ((plane, g), mom) in planes.iter_mut().zip(grads).zip(&mut self.plane_moments) {
            let mut p = [
                plane.centre.x,
                plane.centre.y,
                plane.centre.z,
                plane.normal.x,
                plane.normal.y,
                plane.normal.z,
                plane.r0_logit,
            ];
            let gv = [
                g.centre.x, g.centre.y, g.centre.z, g.normal.x, g.normal.y, g.normal.z, g.r0_logit,
            ];
            let groups: [(std::ops::Range<usize>, f64); 3] =
                [(0..3, r.plane_centre * self.extent), (3..6, r.plane_normal), (6..7, r.plane_r0)];
            for (range, lr) in groups {
                adam(
                    &mut p[range.clone()],
                    &gv[range.clone()],
                    &mut mom.m[range.clone()],
                    &mut mom.v[range],
                    &AdamRate::uniform(lr),
                    t,
                    &AdamSettings::default(),
                );
            }
            plane.centre = glam::DVec3::new(p[0], p[1], p[2]);
            plane.normal = glam::DVec3::new(p[3], p[4], p[5]);
            plane.r0_logit = p[6];
            plane.orthogonalise_axis();
        }
        self.scene.set_planes(&planes).context("a plane step left an invalid plane")?;
        Ok(())
    }
}

fn zero_moments(ctx: &GpuContext, scene: &GpuScene) -> Vec<AdamMoments> {
    let n = u64::from(scene.len());
    ATTRIBUTES
        .iter()
        .zip(scene.attribute_widths())
        .map(|(name, w)| AdamMoments::zeros(ctx, name, n * u64::from(w)))
        .collect()
}

fn to_f64(im: &Image<f32>) -> Image<f64> {
    Image {
        width: im.width,
        height: im.height,
        channels: im.channels,
        data: im.data.iter().map(|&v| f64::from(v)).collect(),
    }
}

fn loss_mse(a: &Image<f32>, b: &Image<f32>) -> f64 {
    let n = a.data.len().max(1) as f64;
    a.data.iter().zip(&b.data).map(|(&x, &y)| (f64::from(x) - f64::from(y)).powi(2)).sum::<f64>()
        / n
}

/// PSNR for data range 1 (infinite for a perfect match).
pub fn psnr_of(mse: f64) -> f64 {
    if mse > 0.0 { -10.0 * mse.log10() } else { f64::INFINITY }
}
