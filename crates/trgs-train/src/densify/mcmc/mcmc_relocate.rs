//! Stage `mcmc_relocate` on the GPU (shaders/training/mcmc_relocate_*.wgsl; twin
//! [`crate::densify::mcmc::plan_relocation`]): 3DGS-MCMC's relocation and growth decided on the
//! GPU from the Gaussians in place. Two rounds of draws in proportion to opacity (weights by
//! opacity bin, scanned; each draw a binary search of the scan): the dead primary Gaussians take
//! copies of live ones, then the set grows with copies of primary ones; a row drawn N - 1 times
//! and its copies take Eq. 9's opacity and scale for N. The passes write the new set's opacities,
//! log scales and `gather_rows` sources; three counters (the dead count and the two rounds'
//! weight totals) are read back, which say how many rows the new set has. A trainer reads them
//! a step late ([`GpuMcmcRelocate::record`], [`PendingMcmcRelocate::settle`]).
use super::relocate::{RelocationLimits, relocation_table, weight_table};
use super::settings::McmcReport;
use crate::gaussians::gather_rows::GatherSources;
use crate::gaussians::state::GaussianState;
use crate::kernels::TRAINING_KERNELS;
use crate::layout::McmcRelocateParams;
use anyhow::Result;
use trgs_core::scene::Attribute;
use trgs_render::toolkit::PrefixSum;
use trgs_render::toolkit::gpu::{self, BufferPool, Kernel, Recorder, grid_1d};
use trgs_render::{GpuContext, GpuScene};

/// The words read back: the dead count and the two rounds' weight totals.
const COUNTERS: usize = 3;

/// The stage's kernels and its Eq. 9 table, built once per run.
#[derive(Debug)]
pub struct GpuMcmcRelocate {
    weights: Kernel,
    draw: Kernel,
    shares: Kernel,
    slots: Kernel,
    append: Kernel,
    scan: PrefixSum,
    share_table: wgpu::Buffer,
}

/// A relocation recorded and submitted whose counters are on their way back: the set it was
/// decided from must stay unchanged in size until it is settled.
#[derive(Debug)]
#[must_use = "a relocation changes nothing until it is settled and applied"]
pub struct PendingMcmcRelocate {
    read: gpu::PendingRead,
    count: u32,
    growth: u32,
    opacity_logits: wgpu::Buffer,
    log_scales: wgpu::Buffer,
    sources: wgpu::Buffer,
}

impl PendingMcmcRelocate {
    /// The relocation, once its three counters have come back (waiting for its own submission
    /// only if they have not).
    pub fn settle(self, ctx: &GpuContext) -> Result<McmcRelocateOutput, gpu::GpuError> {
        gpu::scoped(ctx, "relocating", || self.settle_scoped(ctx))
    }

    fn settle_scoped(self, ctx: &GpuContext) -> Result<McmcRelocateOutput, gpu::GpuError> {
        let c: Vec<u32> = self.read.read(ctx, 4 * COUNTERS)?;
        let (dead_count, first_total, second_total) = (c[0], c[1], c[2]);
        let report = McmcReport {
            relocated: if first_total > 0 { dead_count as usize } else { 0 },
            added: if second_total > 0 { self.growth as usize } else { 0 },
        };
        let len = self.count + report.added as u32;
        let (opacity, log_scales) = (self.opacity_logits, self.log_scales);
        // Without growth draws (no primary Gaussian) the working rows past `n` are unused.
        let (opacity, log_scales) = if len == self.count + self.growth {
            (opacity, log_scales)
        } else {
            let mut enc = ctx.device.create_command_encoder(&Default::default());
            let mut cut = |b: &wgpu::Buffer, words: u32, label: &str| {
                let out = gpu::storage_words(ctx, label, words);
                enc.copy_buffer_to_buffer(b, 0, &out, 0, u64::from(words) * 4);
                out
            };
            let o = cut(&opacity, len, "trgs.mcmc_relocate.opacity_logits");
            let l = cut(&log_scales, 3 * len, "trgs.mcmc_relocate.log_scales");
            ctx.queue.submit([enc.finish()]);
            (o, l)
        };
        Ok(McmcRelocateOutput {
            sources: GatherSources::from_buffer(self.sources, len),
            opacity_logits: opacity,
            log_scales,
            report,
            count: self.count,
        })
    }
}

/// A relocation decided on the GPU: the new set's sources and the attributes it gives whole.
#[derive(Debug)]
pub struct McmcRelocateOutput {
    pub sources: GatherSources,
    pub opacity_logits: wgpu::Buffer,
    pub log_scales: wgpu::Buffer,
    pub report: McmcReport,
    /// The size of the set it was decided for.
    count: u32,
}

impl McmcRelocateOutput {
    /// The size of the set the relocation was decided for.
    pub fn count(&self) -> usize {
        self.count as usize
    }
}

impl GpuMcmcRelocate {
    pub fn new(ctx: &GpuContext) -> Self {
        let k = &TRAINING_KERNELS;
        Self {
            weights: k.mcmc_relocate_weights.build(ctx),
            draw: k.mcmc_relocate_draw.build(ctx),
            shares: k.mcmc_relocate_shares.build(ctx),
            slots: k.mcmc_relocate_slots.build(ctx),
            append: k.mcmc_relocate_append.build(ctx),
            scan: PrefixSum::new(ctx),
            share_table: gpu::storage_init(ctx, "trgs.mcmc_relocate.shares", relocation_table()),
        }
    }

    /// Whether a set of `n` Gaussians growing by `growth` fits the stage, which binds each
    /// per-Gaussian buffer whole (the new log scales, 12 bytes per row, are the widest). Larger
    /// sets are planned on the CPU.
    pub fn fits(ctx: &GpuContext, n: usize, growth: usize) -> bool {
        ((n + growth) as u64) * 12 <= ctx.binding_limit() && n + growth < (1 << 30)
    }

    /// Decide on the GPU: record and submit the passes, with the three counters' readback
    /// behind them, without waiting for either ([`PendingMcmcRelocate::settle`] reads them).
    pub fn record(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        limits: &RelocationLimits,
        growth: u32,
        seeds: [u32; 2],
    ) -> Result<PendingMcmcRelocate, gpu::GpuError> {
        let n = scene.len();
        let scopes = gpu::ErrorScopes::open(ctx, "deciding the relocation");
        let b = RelocationBuffers::new(ctx, n, limits, growth, seeds);
        let mut pool = BufferPool::default();
        let mut rec = Recorder::new(ctx, "trgs.mcmc_relocate", false);
        rec.encoder.clear_buffer(&b.counts, 0, None);
        if n > 0 {
            self.record_relocation(ctx, &mut rec, &mut pool, scene, &b);
            // Without growth the third counter stays 0 (cleared): nothing is added.
            if growth > 0 {
                self.record_growth(ctx, &mut rec, &mut pool, n, &b);
            }
        }
        let read = rec.submit_read(ctx, &b.counts, 4 * COUNTERS);
        let read = scopes.close_after(read)?;
        Ok(PendingMcmcRelocate {
            read,
            count: n,
            growth,
            opacity_logits: b.opacity,
            log_scales: b.log_scales,
            sources: b.sources,
        })
    }

    /// The first round: every dead Gaussian's slot gets a live one drawn by weight (weights,
    /// scans of the dead and the weights, draw, shares, slots); the dead and weight totals go
    /// to the first two counters.
    fn record_relocation(
        &self,
        ctx: &GpuContext,
        rec: &mut Recorder,
        pool: &mut BufferPool,
        scene: &GpuScene,
        b: &RelocationBuffers,
    ) {
        let n = scene.len();
        let p = scene.parameters();
        let (old_opacity, old_log_scales) = (p[Attribute::OpacityLogits], p[Attribute::LogScales]);
        let populations = scene.populations();
        let per_gaussian = grid_1d(n.div_ceil(256));
        let mut scan = |rec: &mut Recorder, label: &str, data: &wgpu::Buffer| {
            self.scan.record(ctx, rec, "mcmc_relocate", pool, label, data, n)
        };
        let weights_inputs = [&b.first, old_opacity, old_log_scales, populations, &b.table];
        let weights_outputs =
            [&b.dead, &b.weights, &b.opacity, &b.log_scales, &b.sources, &b.tally];
        let g = bind(ctx, &self.weights, &[&weights_inputs[..], &weights_outputs[..]].concat());
        rec.dispatch("mcmc_relocate", &self.weights, &g, per_gaussian);
        let dead_total = scan(rec, "trgs.mcmc_relocate.dead", &b.dead);
        let first_total = scan(rec, "trgs.mcmc_relocate.weights1", &b.weights);
        let draw = [&b.first, &dead_total, &first_total, &b.weights, &b.tally, &b.draws];
        let g = bind(ctx, &self.draw, &draw);
        rec.dispatch("mcmc_relocate", &self.draw, &g, per_gaussian);
        let shares = [&b.first, &b.tally, &self.share_table, &b.opacity, &b.log_scales, &b.sources];
        let g = bind(ctx, &self.shares, &shares);
        rec.dispatch("mcmc_relocate", &self.shares, &g, per_gaussian);
        let slots_inputs = [&b.first, old_opacity, populations, &b.dead, &first_total, &b.draws];
        let slots_outputs = [&b.table, &b.opacity, &b.log_scales, &b.sources, &b.weights, &b.tally];
        let g = bind(ctx, &self.slots, &[&slots_inputs[..], &slots_outputs[..]].concat());
        rec.dispatch("mcmc_relocate", &self.slots, &g, per_gaussian);
        for (k, total) in [&dead_total, &first_total].into_iter().enumerate() {
            rec.encoder.copy_buffer_to_buffer(total, 0, &b.counts, 4 * k as u64, 4);
        }
    }

    /// The second round: `growth` Gaussians drawn by weight among all and appended after the
    /// set (scan, draw, shares, append); the weight total goes to the third counter.
    fn record_growth(
        &self,
        ctx: &GpuContext,
        rec: &mut Recorder,
        pool: &mut BufferPool,
        n: u32,
        b: &RelocationBuffers,
    ) {
        let label = "trgs.mcmc_relocate.weights2";
        let second_total = self.scan.record(ctx, rec, "mcmc_relocate", pool, label, &b.weights, n);
        rec.encoder.copy_buffer_to_buffer(&second_total, 0, &b.counts, 8, 4);
        let per_draw = grid_1d(b.growth.div_ceil(256));
        let draw = [&b.second, &b.growth_count, &second_total, &b.weights, &b.tally, &b.draws];
        let g = bind(ctx, &self.draw, &draw);
        rec.dispatch("mcmc_relocate", &self.draw, &g, per_draw);
        let shares =
            [&b.second, &b.tally, &self.share_table, &b.opacity, &b.log_scales, &b.sources];
        let g = bind(ctx, &self.shares, &shares);
        rec.dispatch("mcmc_relocate", &self.shares, &g, grid_1d(n.div_ceil(256)));
        let append = [&b.second, &second_total, &b.draws, &b.opacity, &b.log_scales, &b.sources];
        let g = bind(ctx, &self.append, &append);
        rec.dispatch("mcmc_relocate", &self.append, &g, per_draw);
    }
}

/// Binds `buffers` whole, in order.
fn bind(ctx: &GpuContext, kernel: &Kernel, buffers: &[&wgpu::Buffer]) -> wgpu::BindGroup {
    let entries: Vec<_> = buffers.iter().map(|b| b.as_entire_binding()).collect();
    kernel.bind(ctx, &entries)
}

/// The buffers of one relocation of a set of `n` growing by `growth`.
struct RelocationBuffers {
    /// The parameters of the two rounds (relocation, growth), each with its seed.
    first: wgpu::Buffer,
    second: wgpu::Buffer,
    /// The weight of each opacity bin (integer, so that both sides draw alike).
    table: wgpu::Buffer,
    dead: wgpu::Buffer,
    weights: wgpu::Buffer,
    tally: wgpu::Buffer,
    draws: wgpu::Buffer,
    /// The new set's opacity logits, log scales and source rows (`n + growth` rows).
    opacity: wgpu::Buffer,
    log_scales: wgpu::Buffer,
    sources: wgpu::Buffer,
    growth: u32,
    growth_count: wgpu::Buffer,
    /// The three counters read back: dead, and the weight totals of the two rounds.
    counts: wgpu::Buffer,
}

impl RelocationBuffers {
    fn new(
        ctx: &GpuContext,
        n: u32,
        limits: &RelocationLimits,
        growth: u32,
        seeds: [u32; 2],
    ) -> Self {
        let rows = n + growth;
        let words = |label: &str, len: u32| gpu::storage_words(ctx, label, len);
        let base = McmcRelocateParams {
            count: n,
            growth,
            dead_logit: limits.dead_logit,
            min_logit: limits.min_logit,
            max_logit: limits.max_logit,
            ..Default::default()
        };
        let params = |seed: u32| {
            gpu::params(ctx, "trgs.mcmc_relocate.params", &McmcRelocateParams { seed, ..base })
        };
        let (first, second) = (params(seeds[0]), params(seeds[1]));
        let table =
            gpu::storage_init(ctx, "trgs.mcmc_relocate.weight_table", &weight_table(n as usize));
        Self {
            first,
            second,
            table,
            dead: words("trgs.mcmc_relocate.dead", n),
            weights: words("trgs.mcmc_relocate.weights", n),
            tally: words("trgs.mcmc_relocate.tally", n),
            draws: words("trgs.mcmc_relocate.draws", n.max(growth)),
            opacity: words("trgs.mcmc_relocate.opacity_logits", rows),
            log_scales: words("trgs.mcmc_relocate.log_scales", 3 * rows),
            sources: words("trgs.mcmc_relocate.sources", rows),
            growth,
            growth_count: gpu::storage_init(ctx, "trgs.mcmc_relocate.growth", &[growth]),
            counts: words("trgs.mcmc_relocate.counts", COUNTERS as u32),
        }
    }
}

// The edit of the set this stage decides, beside the stage (the set knows no strategy).
impl GaussianState {
    /// Relocate by a plan decided on the GPU (stage `mcmc_relocate`): the parameters and moments
    /// gathered by its sources, with its opacities and log scales.
    pub fn apply_mcmc_relocate(&mut self, plan: &McmcRelocateOutput) -> Result<()> {
        let given = [
            (Attribute::OpacityLogits, plan.opacity_logits.clone()),
            (Attribute::LogScales, plan.log_scales.clone()),
        ];
        self.rebuild("relocating", &plan.sources, &given, |_, _, _, _| {})
    }
}
