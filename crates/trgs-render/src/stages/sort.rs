//! Stage `sort` (shaders/render/sort_count.wgsl and shaders/render/sort_scatter.wgsl; twins
//! `trgs_core::reference::sort_keys` and `depth_order`): a stable LSD radix sort of 32-bit keys
//! with their 32-bit values, in digits of SORT_RADIX_BITS bits. The caller names the key bits
//! to sort: the key list the bits a tile index can have, the depth order the 32 depth bits. Each
//! pass counts digits per block, scans the digit-major histogram with `prefix_sum`, and scatters
//! stably. A list of two pages ([`Paged`]: the frame's tile keys can outgrow one binding) runs
//! the `_paged` kernels, which pick the page by the index.
use super::{ItemCount, Stage, prefix_sum};
use crate::GpuContext;
use crate::gpu::{self, BufferPool, Recorder, grid_1d};
use crate::layout::{SORT_RADIX, SORT_RADIX_BITS, SortParams};
use crate::toolkit::paged::Paged;

/// Keys and their values, sorted together, in pages of the same length.
#[derive(Clone, Debug)]
pub struct KeyList {
    pub keys: Paged,
    pub values: Paged,
}

impl KeyList {
    /// A list of `len` pairs in pages of `page_len` from `pool`, labelled `{label}.keys.p{k}`
    /// and `{label}.values.p{k}`.
    pub fn from_pool(
        ctx: &GpuContext,
        pool: &mut BufferPool,
        label: &str,
        len: u32,
        page_len: u32,
    ) -> Self {
        Self {
            keys: Paged::from_pool(ctx, pool, &format!("{label}.keys"), len, page_len, 4),
            values: Paged::from_pool(ctx, pool, &format!("{label}.values"), len, page_len, 4),
        }
    }

    /// Pairs in the first page (the kernels' `page` parameter).
    pub fn first_page_len(&self) -> u32 {
        self.keys.first_page_len()
    }

    pub fn is_paged(&self) -> bool {
        self.keys.is_paged()
    }
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
    let alt =
        KeyList::from_pool(s.ctx, pool, &format!("{label}.alt"), capacity, list.keys.page_len());
    let paged = list.is_paged();
    let page = list.first_page_len();
    let num_blocks = capacity.div_ceil(s.ctx.capabilities.block_width.sort_block());
    let hist = pool.get(s.ctx, &format!("{label}.hist"), u64::from(num_blocks * SORT_RADIX) * 4);
    let (mut src, mut dst) = (list.clone(), alt);
    for &shift in shifts {
        let groups = grid_1d(num_blocks);
        let spread = count.spread(groups);
        let params =
            SortParams { count: capacity, shift, num_blocks, spread, page, ..Default::default() };
        let block = gpu::params(s.ctx, "trgs.sort.params", &params);
        // SortParams::count is the block's first word.
        count.write_into(rec, &block);
        let count_k = if paged { &s.kernels.sort_count_paged } else { &s.kernels.sort_count };
        let mut entries =
            vec![block.as_entire_binding(), src.keys.first_page(), hist.as_entire_binding()];
        entries.extend(src.keys.second_page());
        let bind = count_k.bind(s.ctx, &entries);
        rec.dispatch(stage, count_k, &bind, groups);
        let columns = ItemCount::Known(num_blocks * SORT_RADIX);
        let hist_label = format!("{label}.hist_scan");
        prefix_sum::record(s, rec, stage, pool, &hist_label, &hist, columns);
        let scatter = if paged { &s.kernels.sort_scatter_paged } else { &s.kernels.sort_scatter };
        let mut entries = vec![
            block.as_entire_binding(),
            src.keys.first_page(),
            src.values.first_page(),
            hist.as_entire_binding(),
            dst.keys.first_page(),
            dst.values.first_page(),
        ];
        entries.extend(src.keys.second_page());
        entries.extend(src.values.second_page());
        entries.extend(dst.keys.second_page());
        entries.extend(dst.values.second_page());
        let bind = scatter.bind(s.ctx, &entries);
        rec.dispatch(stage, scatter, &bind, groups);
        std::mem::swap(&mut src, &mut dst);
    }
    src
}
