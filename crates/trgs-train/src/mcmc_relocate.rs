//! Stage `mcmc_relocate` on the GPU (shaders/training/mcmc_relocate_*.wgsl; twin
//! [`crate::densify::mcmc::plan_relocation`]): 3DGS-MCMC's relocation and growth decided on the
//! GPU from the Gaussians in place. Two rounds of draws in proportion to opacity (weights by
//! opacity bin, scanned; each draw a binary search of the scan): the dead primary Gaussians take
//! copies of live ones, then the set grows with copies of primary ones; a row drawn N - 1 times
//! and its copies take Eq. 9's opacity and scale for N. The passes write the new set's opacities,
//! log scales and `gather_rows` sources; three counters (the dead count and the two rounds'
//! weight totals) are read back, which say how many rows the new set has. A trainer reads them
//! a step late ([`GpuMcmcRelocate::record`], [`PendingMcmcRelocate::settle`]).
use crate::densify::McmcReport;
use crate::densify::mcmc::{RelocationLimits, relocation_table, weight_table};
use crate::gather_rows::GatherSources;
use crate::kernels::TRAINING_KERNELS;
use crate::layout::McmcRelocateParams;
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
        let rows = n + growth;
        let scopes = gpu::ErrorScopes::open(ctx, "deciding the relocation");
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
        let dead = words("trgs.mcmc_relocate.dead", n);
        let weights = words("trgs.mcmc_relocate.weights", n);
        let tally = words("trgs.mcmc_relocate.tally", n);
        let draws = words("trgs.mcmc_relocate.draws", n.max(growth));
        let opacity = words("trgs.mcmc_relocate.opacity_logits", rows);
        let log_scales = words("trgs.mcmc_relocate.log_scales", 3 * rows);
        let sources = words("trgs.mcmc_relocate.sources", rows);
        let growth_count = gpu::storage_init(ctx, "trgs.mcmc_relocate.growth", &[growth]);
        let counts = words("trgs.mcmc_relocate.counts", COUNTERS as u32);
        let p = scene.parameters();
        let (old_opacity, old_log_scales) = (p[Attribute::OpacityLogits], p[Attribute::LogScales]);
        let populations = scene.populations();
        let per_gaussian = grid_1d(n.div_ceil(256));
        let mut pool = BufferPool::default();
        let mut rec = Recorder::new(ctx, "trgs.mcmc_relocate", false);
        rec.encoder.clear_buffer(&counts, 0, None);
        if n > 0 {
            let bind = |k: &Kernel, b: &[&wgpu::Buffer]| {
                let entries: Vec<_> = b.iter().map(|b| b.as_entire_binding()).collect();
                k.bind(ctx, &entries)
            };
            let mut scan = |rec: &mut Recorder, label: &str, data: &wgpu::Buffer| {
                self.scan.record(ctx, rec, "mcmc_relocate", &mut pool, label, data, n)
            };
            let g = bind(
                &self.weights,
                &[
                    &first,
                    old_opacity,
                    old_log_scales,
                    populations,
                    &table,
                    &dead,
                    &weights,
                    &opacity,
                    &log_scales,
                    &sources,
                    &tally,
                ],
            );
            rec.dispatch("mcmc_relocate", &self.weights, &g, per_gaussian);
            let dead_total = scan(&mut rec, "trgs.mcmc_relocate.dead", &dead);
            let first_total = scan(&mut rec, "trgs.mcmc_relocate.weights1", &weights);
            let g =
                bind(&self.draw, &[&first, &dead_total, &first_total, &weights, &tally, &draws]);
            rec.dispatch("mcmc_relocate", &self.draw, &g, per_gaussian);
            let g = bind(
                &self.shares,
                &[&first, &tally, &self.share_table, &opacity, &log_scales, &sources],
            );
            rec.dispatch("mcmc_relocate", &self.shares, &g, per_gaussian);
            let g = bind(
                &self.slots,
                &[
                    &first,
                    old_opacity,
                    populations,
                    &dead,
                    &first_total,
                    &draws,
                    &table,
                    &opacity,
                    &log_scales,
                    &sources,
                    &weights,
                    &tally,
                ],
            );
            rec.dispatch("mcmc_relocate", &self.slots, &g, per_gaussian);
            for (k, total) in [&dead_total, &first_total].into_iter().enumerate() {
                rec.encoder.copy_buffer_to_buffer(total, 0, &counts, 4 * k as u64, 4);
            }
            // Without growth the third counter stays 0 (cleared): nothing is added.
            if growth > 0 {
                let second_total = scan(&mut rec, "trgs.mcmc_relocate.weights2", &weights);
                rec.encoder.copy_buffer_to_buffer(&second_total, 0, &counts, 8, 4);
                let per_draw = grid_1d(growth.div_ceil(256));
                let g = bind(
                    &self.draw,
                    &[&second, &growth_count, &second_total, &weights, &tally, &draws],
                );
                rec.dispatch("mcmc_relocate", &self.draw, &g, per_draw);
                let g = bind(
                    &self.shares,
                    &[&second, &tally, &self.share_table, &opacity, &log_scales, &sources],
                );
                rec.dispatch("mcmc_relocate", &self.shares, &g, per_gaussian);
                let g = bind(
                    &self.append,
                    &[&second, &second_total, &draws, &opacity, &log_scales, &sources],
                );
                rec.dispatch("mcmc_relocate", &self.append, &g, per_draw);
            }
        }
        let read = rec.submit_read(ctx, &counts, 4 * COUNTERS);
        let read = scopes.close_after(read)?;
        Ok(PendingMcmcRelocate {
            read,
            count: n,
            growth,
            opacity_logits: opacity,
            log_scales,
            sources,
        })
    }
}
