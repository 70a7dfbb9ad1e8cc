//! Stage `prefix_sum` (shaders/render/prefix_sum.wgsl and shaders/render/prefix_sum_add.wgsl;
//! twin `trgs_core::reference::prefix_sum`): an in-place exclusive scan of u32 values, block by
//! block, with the block totals scanned recursively and added back.
use super::{ItemCount, Stage};
use crate::gpu::{self, BufferPool, Kernel, Recorder, grid_1d};
use crate::layout::ScanParams;

/// Scan `count` values of `data` in place (a count known on the GPU only leaves the values past
/// it untouched); returns the buffer whose first u32 is the total. `stage` names the dispatches
/// in the stage timings (the stage the scan serves: the sorts' histograms are theirs), `label`
/// the temporaries in `pool`.
#[allow(clippy::too_many_arguments)]
pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    stage: &'static str,
    pool: &mut BufferPool,
    label: &str,
    data: &wgpu::Buffer,
    count: ItemCount<'_>,
) -> wgpu::Buffer {
    let scan = Scan { stage, label, kernel: &s.kernels.prefix_sum };
    scan_level(s.into(), rec, pool, &scan, data, count, 0)
}

/// Scan the set bits of `words` words of the bit mask `data` in place: each word becomes the
/// number of bits set in the words before it. Returns the buffer whose first u32 is the total.
#[allow(clippy::too_many_arguments)]
pub fn record_bits(
    s: Stage<'_>,
    rec: &mut Recorder,
    stage: &'static str,
    pool: &mut BufferPool,
    label: &str,
    data: &wgpu::Buffer,
    words: u32,
) -> wgpu::Buffer {
    let scan = Scan { stage, label, kernel: &s.kernels.prefix_sum_bits };
    scan_level(s.into(), rec, pool, &scan, data, ItemCount::Known(words), 0)
}

/// One scan's names and its first level's kernel (the levels above scan plain sums).
struct Scan<'a> {
    stage: &'static str,
    label: &'a str,
    kernel: &'a Kernel,
}

/// The kernels of the levels above the first (plain sums), and the join.
#[derive(Clone, Copy)]
struct Levels<'a> {
    ctx: &'a crate::GpuContext,
    sums: &'a Kernel,
    add: &'a Kernel,
}

impl<'a> From<Stage<'a>> for Levels<'a> {
    fn from(s: Stage<'a>) -> Self {
        Self { ctx: s.ctx, sums: &s.kernels.prefix_sum, add: &s.kernels.prefix_sum_add }
    }
}

fn scan_level(
    s: Levels<'_>,
    rec: &mut Recorder,
    pool: &mut BufferPool,
    scan: &Scan<'_>,
    data: &wgpu::Buffer,
    count: ItemCount<'_>,
    level: u32,
) -> wgpu::Buffer {
    let label = scan.label;
    let capacity = count.capacity();
    let blocks = capacity.div_ceil(s.ctx.capabilities.block_width.scan_block());
    let sums = pool.get(s.ctx, &format!("{label}.block_sums{level}"), u64::from(blocks.max(1)) * 4);
    if capacity == 0 {
        rec.encoder.clear_buffer(&sums, 0, None);
        return sums;
    }
    let groups = grid_1d(blocks);
    let params =
        ScanParams { count: capacity, blocks, spread: count.spread(groups), ..Default::default() };
    let block = gpu::params(s.ctx, "trgs.prefix_sum.params", &params);
    count.write_into(rec, &block);
    let bind = scan.kernel.bind(
        s.ctx,
        &[block.as_entire_binding(), data.as_entire_binding(), sums.as_entire_binding()],
    );
    rec.dispatch(scan.stage, scan.kernel, &bind, groups);
    if blocks == 1 {
        return sums;
    }
    let sums_count = ItemCount::Known(blocks);
    let sums_scan = Scan { kernel: s.sums, ..*scan };
    let total = scan_level(s, rec, pool, &sums_scan, &sums, sums_count, level + 1);
    let add = s.add;
    let bind = add.bind(
        s.ctx,
        &[block.as_entire_binding(), data.as_entire_binding(), sums.as_entire_binding()],
    );
    rec.dispatch(scan.stage, add, &bind, groups);
    total
}

/// Stage `prefix_sum` for stages outside the renderer (trgs-train's densification): the scan's
/// two kernels, built once.
#[derive(Debug)]
pub struct PrefixSum {
    sums: Kernel,
    add: Kernel,
}

impl PrefixSum {
    pub fn new(ctx: &crate::GpuContext) -> Self {
        let k = &crate::kernels::RENDER_KERNELS;
        Self { sums: k.prefix_sum.build(ctx), add: k.prefix_sum_add.build(ctx) }
    }

    /// Scan the first `count` values of `data` (bound whole) in place into their exclusive
    /// prefix sums; returns the buffer whose first u32 is the total. `stage` names the
    /// dispatches, `label` the temporaries in `pool`.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        ctx: &crate::GpuContext,
        rec: &mut Recorder,
        stage: &'static str,
        pool: &mut BufferPool,
        label: &str,
        data: &wgpu::Buffer,
        count: u32,
    ) -> wgpu::Buffer {
        let levels = Levels { ctx, sums: &self.sums, add: &self.add };
        let scan = Scan { stage, label, kernel: &self.sums };
        scan_level(levels, rec, pool, &scan, data, ItemCount::Known(count), 0)
    }
}
