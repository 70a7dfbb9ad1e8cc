//! The Gaussians under optimisation: their parameters on the GPU and Adam's moments, with the
//! operations that edit both together (the shared operations every densification strategy
//! uses), so that no edit leaves a parameter and its moments out of step.
use super::adam::AdamMoments;
use super::gather_rows::{GatherSources, GpuRowGather};
use super::plan::{Geometry, RowPlan, TrainState};
use crate::densify::classic::opacity_reset::GpuOpacityReset;
use anyhow::{Context, Result};
use trgs_core::scene::{Attribute, Gaussians, PerAttribute, ReflectionPlane};
use trgs_render::toolkit::gpu::Recorder;
use trgs_render::{GpuContext, GpuScene};

/// Parameters and Adam moments of every Gaussian, on the GPU.
#[derive(Debug)]
pub struct GaussianState {
    ctx: GpuContext,
    scene: GpuScene,
    moments: PerAttribute<AdamMoments>,
    /// Rebuilds the parameters and moments by a [`RowPlan`] on the GPU.
    gather: GpuRowGather,
    opacity_reset: GpuOpacityReset,
}

impl GaussianState {
    /// Upload `gaussians` and `planes` with zero moments.
    pub fn new(
        ctx: &GpuContext,
        gaussians: &Gaussians<f32>,
        planes: &[ReflectionPlane],
    ) -> Result<Self> {
        let scene = GpuScene::upload(ctx, gaussians, planes).context("uploading the Gaussians")?;
        let n = u64::from(scene.len());
        let widths = scene.attribute_widths();
        let moments =
            PerAttribute::from_fn(|a| AdamMoments::zeros(ctx, a.name(), n * u64::from(widths[a])));
        Ok(Self::holding(ctx, scene, moments))
    }

    /// Upload `state` (parameters and moments, a checkpoint's or an edit's) and `planes`.
    pub fn from_state(
        ctx: &GpuContext,
        state: &TrainState,
        planes: &[ReflectionPlane],
    ) -> Result<Self> {
        let (scene, moments) = upload(ctx, state, planes)?;
        Ok(Self::holding(ctx, scene, moments))
    }

    pub fn scene(&self) -> &GpuScene {
        &self.scene
    }

    /// The scene, for edits that keep the Gaussians (the trainer's planes).
    pub(crate) fn scene_mut(&mut self) -> &mut GpuScene {
        &mut self.scene
    }

    pub fn moments(&self) -> &PerAttribute<AdamMoments> {
        &self.moments
    }

    pub fn len(&self) -> usize {
        self.scene.len() as usize
    }

    pub fn is_empty(&self) -> bool {
        self.scene.is_empty()
    }

    /// The current Gaussians, read back.
    pub fn gaussians(&self) -> Result<Gaussians<f32>> {
        Ok(self.scene.read(&self.ctx)?)
    }

    /// The parameters and Adam moments, read back.
    pub fn read(&self) -> Result<TrainState> {
        let read = |b: &wgpu::Buffer, len: u64| {
            trgs_render::toolkit::gpu::read_buffer::<f32>(&self.ctx, b, 0, len as usize)
        };
        let (mut m, mut v) = (PerAttribute::default(), PerAttribute::default());
        for (a, mo) in self.moments.iter() {
            m[a] = read(&mo.m, mo.len)?;
            v[a] = read(&mo.v, mo.len)?;
        }
        Ok(TrainState { gaussians: self.gaussians()?, m, v })
    }

    /// Replace the parameters and moments (the planes stay).
    pub fn replace(&mut self, state: &TrainState) -> Result<()> {
        let planes = self.scene.planes().to_vec();
        (self.scene, self.moments) = upload(&self.ctx, state, &planes)?;
        Ok(())
    }

    /// The attributes densification and relocation decide from, read back (15 words per
    /// Gaussian; [`GaussianState::read`] reads about 180 at SH degree 3).
    pub fn geometry(&self) -> Result<Geometry> {
        let (ctx, n) = (&self.ctx, self.len());
        let p = self.scene.parameters();
        Ok(Geometry {
            means: trgs_render::toolkit::gpu::read_buffer(ctx, p[Attribute::Means], 0, n)?,
            rotations: trgs_render::toolkit::gpu::read_buffer(ctx, p[Attribute::Rotations], 0, n)?,
            log_scales: trgs_render::toolkit::gpu::read_buffer(ctx, p[Attribute::LogScales], 0, n)?,
            opacity_logits: trgs_render::toolkit::gpu::read_buffer(
                ctx,
                p[Attribute::OpacityLogits],
                0,
                n,
            )?,
            populations: self.scene.read_populations(ctx)?,
        })
    }

    /// Rebuild the parameters and their moments by `plan` on the GPU (stage `gather_rows`).
    pub fn apply_plan(&mut self, plan: &RowPlan) -> Result<()> {
        self.check_plan(plan)?;
        let ctx = self.ctx.clone();
        trgs_render::toolkit::gpu::scoped(&ctx, "densifying", || {
            let (scene, moments) = self.gather.apply(&ctx, &self.scene, &self.moments, plan)?;
            self.scene = scene;
            self.moments = moments;
            Ok(())
        })
    }

    /// Replace the parameters and moments by those `gather_rows` makes of `sources`, with the
    /// `given` attributes, and `then`'s edits of the new scene (from the old) in the same
    /// submission.
    pub(crate) fn rebuild(
        &mut self,
        what: &'static str,
        sources: &GatherSources,
        given: &[(Attribute, wgpu::Buffer)],
        then: impl FnOnce(&GpuContext, &mut Recorder, &GpuScene, &GpuScene),
    ) -> Result<()> {
        let ctx = self.ctx.clone();
        trgs_render::toolkit::gpu::scoped(&ctx, what, || {
            let old = &self.scene;
            let (scene, moments) = self.gather.apply_sources(
                &ctx,
                old,
                &self.moments,
                sources,
                given,
                |rec, new| then(&ctx, rec, old, new),
            )?;
            self.scene = scene;
            self.moments = moments;
            Ok(())
        })
    }

    /// [`GaussianState::apply_plan`] through the CPU: the whole state read back, rebuilt by
    /// [`RowPlan::apply`] (the twin) and uploaded. For tests and the benchmark.
    pub fn apply_plan_on_cpu(&mut self, plan: &RowPlan) -> Result<()> {
        self.check_plan(plan)?;
        let state = self.read()?;
        self.replace(&plan.apply(&state))
    }

    fn check_plan(&self, plan: &RowPlan) -> Result<()> {
        let n = self.len();
        if let Some(&(i, _)) = plan.sources.iter().find(|&&(i, _)| i >= n) {
            anyhow::bail!("a densification plan copies Gaussian {i} of {n}");
        }
        let rows = plan.sources.len();
        let lengths = [
            plan.means.as_ref().map(Vec::len),
            plan.log_scales.as_ref().map(Vec::len),
            plan.opacity_logits.as_ref().map(Vec::len),
        ];
        if lengths.iter().flatten().any(|&l| l != rows) {
            anyhow::bail!("a densification plan of {rows} rows gives attributes of {lengths:?}");
        }
        if !plan.given_are_finite() {
            anyhow::bail!("densification made a non-finite mean, scale or opacity");
        }
        Ok(())
    }

    /// Cap every opacity logit at `cap` and restart the opacities' Adam moments (3DGS's opacity
    /// reset), on the GPU (stage `opacity_reset`); the other parameters and moments stay.
    pub fn opacity_reset(&mut self, cap: f32) -> Result<()> {
        let ctx = self.ctx.clone();
        trgs_render::toolkit::gpu::scoped(&ctx, "resetting the opacities", || {
            let mut rec = Recorder::new(&ctx, "trgs.opacity_reset", false);
            self.opacity_reset.record(&ctx, &mut rec, &self.scene, cap);
            let moments = &self.moments[Attribute::OpacityLogits];
            rec.encoder.clear_buffer(&moments.m, 0, None);
            rec.encoder.clear_buffer(&moments.v, 0, None);
            rec.submit(&ctx)?;
            Ok(())
        })
    }
}

impl GaussianState {
    fn holding(ctx: &GpuContext, scene: GpuScene, moments: PerAttribute<AdamMoments>) -> Self {
        let (gather, opacity_reset) = (GpuRowGather::new(ctx), GpuOpacityReset::new(ctx));
        Self { ctx: ctx.clone(), scene, moments, gather, opacity_reset }
    }
}

/// `state`'s parameters and moments on the GPU (its moments' lengths checked), with `planes`.
fn upload(
    ctx: &GpuContext,
    state: &TrainState,
    planes: &[ReflectionPlane],
) -> Result<(GpuScene, PerAttribute<AdamMoments>)> {
    let n = state.gaussians.len();
    let widths = trgs_core::scene::attribute_widths(state.gaussians.sh_coeffs());
    for a in Attribute::ALL {
        let want = n * widths[a];
        if state.m[a].len() != want || state.v[a].len() != want {
            anyhow::bail!(
                "the Adam moments of {} hold {} and {} values for {n} Gaussians ({want} \
                 expected)",
                a.name(),
                state.m[a].len(),
                state.v[a].len()
            );
        }
    }
    let scene = GpuScene::upload(ctx, &state.gaussians, planes)
        .context("uploading the edited Gaussians")?;
    let moments = PerAttribute::from_fn(|a| {
        AdamMoments::from_values(ctx, a.name(), &state.m[a], &state.v[a])
    });
    Ok((scene, moments))
}
