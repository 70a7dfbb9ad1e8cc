//! Stage `sort` (shaders/sort_count.wgsl and sort_scatter.wgsl; twins
//! `trgs_core::reference::sort_keys` and `depth_order`): a stable LSD radix sort of 32-bit keys
//! with their 32-bit values, in digits of SORT_RADIX_BITS bits. The caller names the key bits
//! to sort: the key list the bits a tile index can have, the depth order the 32 depth bits. Each
//! pass counts digits per block, scans the digit-major histogram with `prefix_sum`, and scatters
//! stably.
use super::{ItemCount, Stage, prefix_sum};
use crate::gpu::{self, BufferPool, Recorder, grid_1d};
use crate::layout::{SORT_RADIX, SORT_RADIX_BITS, SortParams};

/// Keys and their values, sorted together.
#[derive(Clone, Debug)]
pub struct KeyList {
    pub keys: wgpu::Buffer,
    pub values: wgpu::Buffer,
}

/// The bit offsets of the passes over the low `bits` bits of the keys.
pub fn digits(bits: u32) -> impl Iterator<Item = u32> {
    (0..bits.div_ceil(SORT_RADIX_BITS)).map(|d| d * SORT_RADIX_BITS)
}

/// Bits needed to hold values below `n`.
pub fn bits_below(n: u32) -> u32 {
    32 - n.saturating_sub(1).leading_zeros()
}

/// Sort the pairs of `list`; returns the buffers holding the result (`list`'s or the pool's
/// alternates, named after `label`). `stage` names the dispatches in the stage timings.
#[allow(clippy::too_many_arguments)]
pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    stage: &'static str,
    pool: &mut BufferPool,
    label: &str,
    list: &KeyList,
    count: ItemCount<'_>,
    shifts: &[u32],
) -> KeyList {
    let capacity = count.capacity();
    if capacity <= 1 || shifts.is_empty() {
        return list.clone();
    }
    let bytes = u64::from(capacity) * 4;
    let alt = KeyList {
        keys: pool.get(s.ctx, &format!("{label}.alt_keys"), bytes),
        values: pool.get(s.ctx, &format!("{label}.alt_values"), bytes),
    };
    let num_blocks = capacity.div_ceil(s.ctx.capabilities.block_width.sort_block());
    let hist = pool.get(s.ctx, &format!("{label}.hist"), u64::from(num_blocks * SORT_RADIX) * 4);
    let (mut src, mut dst) = (list.clone(), alt);
    for &shift in shifts {
        let groups = grid_1d(num_blocks);
        let spread = count.spread(groups);
        let params = SortParams { count: capacity, shift, num_blocks, spread };
        let block = gpu::params(s.ctx, "trgs.sort.params", &params);
        // SortParams::count is the block's first word.
        count.write_into(rec, &block);
        let count_k = &s.kernels.sort_count;
        let bind = count_k.bind(
            s.ctx,
            &[block.as_entire_binding(), src.keys.as_entire_binding(), hist.as_entire_binding()],
        );
        rec.dispatch(stage, count_k, &bind, groups);
        let columns = ItemCount::Known(num_blocks * SORT_RADIX);
        let hist_label = format!("{label}.hist_scan");
        prefix_sum::record(s, rec, stage, pool, &hist_label, &hist, columns);
        let scatter = &s.kernels.sort_scatter;
        let bind = scatter.bind(
            s.ctx,
            &[
                block.as_entire_binding(),
                src.keys.as_entire_binding(),
                src.values.as_entire_binding(),
                hist.as_entire_binding(),
                dst.keys.as_entire_binding(),
                dst.values.as_entire_binding(),
            ],
        );
        rec.dispatch(stage, scatter, &bind, groups);
        std::mem::swap(&mut src, &mut dst);
    }
    src
}
