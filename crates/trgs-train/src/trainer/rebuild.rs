//! The trainer's densification and relocation: decisions on the CPU from the attributes read
//! back ([`Trainer::geometry`]), the rebuild on the GPU (`gather_rows`).
use super::Trainer;
use crate::densify::{DensifyReport, Geometry, RowPlan, plan_densify};
use crate::mcmc::{McmcReport, plan_relocation};
use anyhow::Result;
use trgs_core::scene::Attribute;

impl Trainer {
    /// The attributes densification and relocation decide from, read back (15 words per
    /// Gaussian; [`Trainer::read_state`] reads about 180 at SH degree 3).
    pub fn geometry(&self) -> Result<Geometry> {
        let (ctx, n) = (&self.ctx, self.scene.len() as usize);
        let p = self.scene.parameters();
        Ok(Geometry {
            means: trgs_render::gpu::read_buffer(ctx, p[Attribute::Means], 0, n)?,
            rotations: trgs_render::gpu::read_buffer(ctx, p[Attribute::Rotations], 0, n)?,
            log_scales: trgs_render::gpu::read_buffer(ctx, p[Attribute::LogScales], 0, n)?,
            opacity_logits: trgs_render::gpu::read_buffer(ctx, p[Attribute::OpacityLogits], 0, n)?,
            populations: self.scene.read_populations(ctx)?,
        })
    }

    /// Rebuild the Gaussians and their moments by `plan` on the GPU (stage `gather_rows`); the
    /// densification statistics start over.
    pub fn apply_plan(&mut self, plan: &RowPlan) -> Result<()> {
        let ctx = self.ctx.clone();
        trgs_render::gpu::scoped(&ctx, "densifying", || self.apply_plan_scoped(plan))
    }

    fn apply_plan_scoped(&mut self, plan: &RowPlan) -> Result<()> {
        self.check_plan(plan)?;
        let (scene, moments) = self.gather.apply(&self.ctx, &self.scene, &self.moments, plan)?;
        self.scene = scene;
        self.moments = moments;
        if let Some((_, stats)) = &mut self.densify {
            stats.reset(&self.ctx, plan.sources.len());
        }
        Ok(())
    }

    /// [`Trainer::apply_plan`] through the CPU: the whole state read back, rebuilt by
    /// [`RowPlan::apply`] (the twin) and uploaded, as densification did before `gather_rows`.
    /// For tests and the benchmark.
    pub fn apply_plan_on_cpu(&mut self, plan: &RowPlan) -> Result<()> {
        self.check_plan(plan)?;
        let state = self.read_state()?;
        self.set_state(&plan.apply(&state))
    }

    fn check_plan(&self, plan: &RowPlan) -> Result<()> {
        let n = self.scene.len() as usize;
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

    /// Classic densification now (the schedule calls it every `every` steps); needs
    /// [`Trainer::enable_densification`].
    pub fn densify_now(&mut self, prune_large: bool) -> Result<DensifyReport> {
        let Some((settings, stats)) = &self.densify else {
            anyhow::bail!("densify_now needs classic densification enabled");
        };
        let (settings, stats) = (settings.clone(), stats.read(&self.ctx)?);
        let geometry = self.geometry()?;
        let (plan, report) =
            plan_densify(&geometry, &stats, &settings, self.extent, prune_large, &mut self.rng);
        self.apply_plan(&plan)?;
        Ok(report)
    }

    /// An MCMC relocation now (the schedule calls it every `every` steps); needs
    /// [`Trainer::enable_mcmc`].
    pub fn relocate_now(&mut self) -> Result<McmcReport> {
        let Some((settings, _)) = &self.mcmc else {
            anyhow::bail!("relocate_now needs MCMC densification enabled");
        };
        let settings = settings.clone();
        let (plan, report) = plan_relocation(&self.geometry()?, &settings, &mut self.rng);
        self.apply_plan(&plan)?;
        Ok(report)
    }
}
