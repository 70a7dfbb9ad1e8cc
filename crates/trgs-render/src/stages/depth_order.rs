//! Stage `depth_order` (shaders/render/depth_order_compact.wgsl, the `sort` kernels, then
//! shaders/render/depth_order_counts.wgsl; twin `trgs_core::reference::depth_order`): the
//! entries that `tile_counts` marked present, every view's together, listed in entry order (a
//! scan of the presence bits), sorted front to back by their depth keys
//! (`trgs_core::reference::depth_key`: 30 bits, five radix passes), and their tile counts in
//! that order.
//!
//! Why: sorting every key by (tile, depth) sorts the 32 depth bits once per key, and a
//! Gaussian has one key per tile it touches (about 3.5 on the room benchmark). Sorting the
//! Gaussians by depth once, emitting their keys in that order and sorting the keys by tile alone
//! (stably) gives the same lists with the depth passes run over the Gaussians instead. The list
//! starts in entry order, so the stable sort leaves depth ties in index order as the twin does
//! (an atomic append would be cheaper but would order ties differently from run to run). The
//! entry count is known on the GPU only: the passes read it there and cover the capacity.
use super::sort::{self, KeyList, digits};
use super::tile_counts::DepthEntries;
use super::{ItemCount, Stage, prefix_sum};
use crate::gpu::{self, BufferPool, Recorder, grid_1d};
use crate::layout::{DEPTH_COUNTS_BLOCK, ScanParams};
use trgs_core::pipeline::DEPTH_KEY_BITS;

/// The sorted entries and their count.
#[derive(Debug)]
pub struct DepthOrder {
    /// Keys: depth bits; values: entry indices, front to back.
    pub list: KeyList,
    /// First u32: how many entries the list holds.
    pub entries: wgpu::Buffer,
}

/// Lists the present entries, sorts them and writes each sorted entry's tile count into
/// `ordered_counts` (nothing past the last entry: its scan reads the count on the GPU too).
pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    pool: &mut BufferPool,
    entries: &DepthEntries,
    ordered_counts: &wgpu::Buffer,
) -> DepthOrder {
    let capacity = entries.capacity;
    // Each presence word's first list slot: the scan of the words' set bits (on a copy: the
    // compaction reads the bits too).
    let words = entries.present_words;
    let label = "trgs.depth_order.slots";
    let slots = pool.get(s.ctx, label, u64::from(words.max(1)) * 4);
    rec.encoder.copy_buffer_to_buffer(&entries.present, 0, &slots, 0, u64::from(words) * 4);
    let total = prefix_sum::record_bits(s, rec, "depth_order", pool, label, &slots, words);
    // One page: the entries' rectangles (8 bytes each) are checked against a binding first.
    let list = KeyList::from_pool(s.ctx, pool, "trgs.depth_order", capacity, capacity.max(1));
    let word_block = gpu::params(
        s.ctx,
        "trgs.depth_order.compact_params",
        &ScanParams { count: words, ..Default::default() },
    );
    let k = &s.kernels.depth_order_compact;
    let bind = k.bind(
        s.ctx,
        &[
            word_block.as_entire_binding(),
            entries.present.as_entire_binding(),
            slots.as_entire_binding(),
            entries.depths.as_entire_binding(),
            list.keys.first_page(),
            list.values.first_page(),
        ],
    );
    rec.dispatch("depth_order", k, &bind, grid_1d(words.div_ceil(256)));
    // The entries fill the first slots of the capacity: spread the workgroups over them.
    let groups = grid_1d(capacity.div_ceil(DEPTH_COUNTS_BLOCK));
    let spread = gpu::spread_step(groups);
    let block = gpu::params(
        s.ctx,
        "trgs.depth_order.params",
        &ScanParams { count: capacity, spread, ..Default::default() },
    );
    let passes: Vec<_> = digits(DEPTH_KEY_BITS).collect();
    let count = ItemCount::OnGpu { counter: &total, capacity };
    let list = sort::record(s, rec, "depth_order", pool, "trgs.depth_order", &list, count, &passes);
    let k = &s.kernels.depth_order_counts;
    let bind = k.bind(
        s.ctx,
        &[
            block.as_entire_binding(),
            total.as_entire_binding(),
            list.values.first_page(),
            entries.rects.as_entire_binding(),
            ordered_counts.as_entire_binding(),
        ],
    );
    rec.dispatch("depth_order", k, &bind, groups);
    DepthOrder { list, entries: total }
}
