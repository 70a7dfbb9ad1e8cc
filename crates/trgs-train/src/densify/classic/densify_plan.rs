//! Stage `densify_plan` on the GPU (shaders/training/densify_plan_*.wgsl; twin
//! [`crate::densify::classic::plan_densify`]): classic densification decided on the GPU, from the
//! statistics `densify_stats` gathered and the Gaussians in place, without reading either back.
//! Four passes and two scans make the `gather_rows` sources of the new set: flag the candidates,
//! rank them (a scan), decide each Gaussian's rows, place them (a scan), write the sources; after
//! the gather, the split children take their means and scales. Only five counters cross to the
//! CPU: the report (cloned, split, pruned, and the Gaussians drawn since the last densification,
//! which scale the next key list) and the rows the rebuild is sized by. A trainer reads them a
//! step late ([`GpuDensifyPlan::record`], [`PendingDensifyPlan::settle`]): the GPU runs the next
//! step meanwhile.
use super::settings::DensifyReport;
use crate::gaussians::gather_rows::GatherSources;
use crate::gaussians::state::GaussianState;
use crate::kernels::TRAINING_KERNELS;
use crate::layout::DensifyPlanParams;
use anyhow::Result;
use trgs_core::scene::Attribute;
use trgs_render::toolkit::PrefixSum;
use trgs_render::toolkit::gpu::{self, BufferPool, Kernel, Recorder, grid_1d};
use trgs_render::{GpuContext, GpuScene};

/// The words read back: cloned, split, pruned, rows, seen.
const COUNTERS: usize = 5;

/// The stage's kernels, built once per run.
#[derive(Debug)]
pub struct GpuDensifyPlan {
    candidates: Kernel,
    rows: Kernel,
    sources: Kernel,
    children: Kernel,
    scan: PrefixSum,
}

/// A plan recorded and submitted whose counters are on their way back: the set it was decided
/// from must stay unchanged in size until it is settled (its values may change: the rows are
/// gathered from them when the plan is applied).
#[derive(Debug)]
#[must_use = "a plan changes nothing until it is settled and applied"]
pub struct PendingDensifyPlan {
    read: gpu::PendingRead,
    sources: wgpu::Buffer,
    params: wgpu::Buffer,
    count: u32,
    decisions: wgpu::Buffer,
    first_rows: wgpu::Buffer,
}

impl PendingDensifyPlan {
    /// The plan, once its five counters have come back (waiting for the plan's own submission
    /// only if they have not).
    pub fn settle(self, ctx: &GpuContext) -> Result<DensifyPlanOutput, gpu::GpuError> {
        let c: Vec<u32> = self.read.read(ctx, 4 * COUNTERS)?;
        let (cloned, split, pruned, rows, seen) = (c[0], c[1], c[2], c[3], c[4]);
        let report = DensifyReport {
            cloned: cloned as usize,
            split: split as usize,
            pruned: pruned as usize,
            seen: seen as usize,
        };
        Ok(DensifyPlanOutput {
            sources: GatherSources::from_buffer(self.sources, rows),
            report,
            params: self.params,
            count: self.count,
            decisions: self.decisions,
            first_rows: self.first_rows,
        })
    }
}

/// A plan decided on the GPU: the sources `gather_rows` copies the new set from, and what the
/// children's pass reads.
#[derive(Debug)]
pub struct DensifyPlanOutput {
    pub sources: GatherSources,
    pub report: DensifyReport,
    params: wgpu::Buffer,
    count: u32,
    decisions: wgpu::Buffer,
    first_rows: wgpu::Buffer,
}

impl DensifyPlanOutput {
    /// The size of the set the plan was decided for.
    pub fn count(&self) -> usize {
        self.count as usize
    }
}

impl GpuDensifyPlan {
    pub fn new(ctx: &GpuContext) -> Self {
        let k = &TRAINING_KERNELS;
        Self {
            candidates: k.densify_plan_candidates.build(ctx),
            rows: k.densify_plan_rows.build(ctx),
            sources: k.densify_plan_sources.build(ctx),
            children: k.densify_plan_children.build(ctx),
            scan: PrefixSum::new(ctx),
        }
    }

    /// Whether a set of `n` Gaussians fits the stage: it binds each per-Gaussian buffer whole
    /// (the statistics and rotations, 16 bytes per Gaussian, are the widest) and the new set's
    /// means (at most two rows per Gaussian). Larger sets are planned on the CPU.
    pub fn fits(ctx: &GpuContext, n: usize) -> bool {
        (n as u64) * 24 <= ctx.binding_limit() && n < (1 << 30)
    }

    /// Decide on the GPU: record and submit the passes, with the five counters' readback
    /// behind them, without waiting for either ([`PendingDensifyPlan::settle`] reads them).
    pub fn record(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        stats: &wgpu::Buffer,
        params: &DensifyPlanParams,
    ) -> Result<PendingDensifyPlan, gpu::GpuError> {
        let n = params.count;
        debug_assert_eq!(n, scene.len(), "a plan of another set");
        let scopes = gpu::ErrorScopes::open(ctx, "deciding the densification");
        let words = |label: &str, len: u32| gpu::storage_words(ctx, label, len);
        let block = gpu::params(ctx, "trgs.densify_plan.params", params);
        let ranks = words("trgs.densify_plan.ranks", n);
        let first_rows = words("trgs.densify_plan.first_rows", n);
        let decisions = words("trgs.densify_plan.decisions", n);
        // At most two rows per Gaussian: a survivor and its clone, or two children.
        let sources = words("trgs.densify_plan.sources", 2 * n);
        let counts = words("trgs.densify_plan.counts", COUNTERS as u32);
        let p = scene.parameters();
        let (opacity, log_scales) = (p[Attribute::OpacityLogits], p[Attribute::LogScales]);
        let groups = grid_1d(n.div_ceil(256));
        let mut pool = BufferPool::default();
        let mut rec = Recorder::new(ctx, "trgs.densify_plan", false);
        rec.encoder.clear_buffer(&counts, 0, None);
        if n > 0 {
            let entries = [&block, stats, opacity, &ranks].map(|b| b.as_entire_binding());
            let bind = self.candidates.bind(ctx, &entries);
            rec.dispatch("densify_plan", &self.candidates, &bind, groups);
            self.scan.record(
                ctx,
                &mut rec,
                "densify_plan",
                &mut pool,
                "trgs.densify_plan.ranks",
                &ranks,
                n,
            );
            let entries =
                [&block, stats, opacity, log_scales, &ranks, &first_rows, &decisions, &counts]
                    .map(|b| b.as_entire_binding());
            let bind = self.rows.bind(ctx, &entries);
            rec.dispatch("densify_plan", &self.rows, &bind, groups);
            let total = self.scan.record(
                ctx,
                &mut rec,
                "densify_plan",
                &mut pool,
                "trgs.densify_plan.first_rows",
                &first_rows,
                n,
            );
            rec.encoder.copy_buffer_to_buffer(&total, 0, &counts, 12, 4);
            let entries =
                [&block, &decisions, &first_rows, &sources].map(|b| b.as_entire_binding());
            let bind = self.sources.bind(ctx, &entries);
            rec.dispatch("densify_plan", &self.sources, &bind, groups);
        }
        let read = rec.submit_read(ctx, &counts, 4 * COUNTERS);
        let read = scopes.close_after(read)?;
        Ok(PendingDensifyPlan { read, sources, params: block, count: n, decisions, first_rows })
    }

    /// Record the children's pass: their means and scales in `new` (gathered by `plan`'s
    /// sources from `old`), from their parents in `old`.
    pub fn record_children(
        &self,
        ctx: &GpuContext,
        rec: &mut Recorder,
        plan: &DensifyPlanOutput,
        old: &GpuScene,
        new: &GpuScene,
    ) {
        if plan.count == 0 || plan.report.split == 0 {
            return;
        }
        let (p, q) = (old.parameters(), new.parameters());
        let entries = [
            &plan.params,
            &plan.decisions,
            &plan.first_rows,
            p[Attribute::Means],
            p[Attribute::Rotations],
            p[Attribute::LogScales],
            q[Attribute::Means],
            q[Attribute::LogScales],
        ]
        .map(|b| b.as_entire_binding());
        let bind = self.children.bind(ctx, &entries);
        rec.dispatch("densify_plan", &self.children, &bind, grid_1d(plan.count.div_ceil(256)));
    }
}

// The edit of the set this stage decides, beside the stage (the set knows no strategy).
impl GaussianState {
    /// Densify by a plan decided on the GPU (stage `densify_plan`): the parameters and moments
    /// gathered by its sources, then the split children's means and scales.
    pub fn apply_densify_plan(
        &mut self,
        planner: &GpuDensifyPlan,
        plan: &DensifyPlanOutput,
    ) -> Result<()> {
        self.rebuild("densifying", &plan.sources, &[], |ctx, rec, old, new| {
            planner.record_children(ctx, rec, plan, old, new)
        })
    }
}
