//! Stage `sort` (shaders/sort_count.wgsl and sort_scatter.wgsl; twin
//! `trgs_core::reference::sort_keys`): a stable LSD radix sort of the (tile, depth) keys with
//! 4-bit digits. Only the bits that can be set are sorted: the 32 depth bits and as many tile bits
//! as the grid needs. Each pass counts digits per block, scans the digit-major histogram with
//! `prefix_sum`, and scatters stably.
use super::emit_keys::Keys;
use super::{Stage, prefix_sum};
use crate::gpu::{self, BufferPool, Recorder, grid_1d};
use crate::layout::{SORT_BLOCK, SortParams};

/// Bits needed to hold tile indices below `tiles`.
pub fn tile_bits(tiles: u32) -> u32 {
    32 - tiles.saturating_sub(1).leading_zeros()
}

/// Sort `count` keys; returns the buffers holding the result (`keys` or the pool's alternates).
pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    pool: &mut BufferPool,
    label: &str,
    keys: &Keys,
    count: u32,
    tile_bits: u32,
) -> Keys {
    if count <= 1 {
        return keys.clone();
    }
    let bytes = u64::from(count) * 4;
    let alt = Keys {
        hi: pool.get(s.ctx, &format!("{label}.alt_hi"), bytes),
        lo: pool.get(s.ctx, &format!("{label}.alt_lo"), bytes),
        values: pool.get(s.ctx, &format!("{label}.alt_values"), bytes),
    };
    let num_blocks = count.div_ceil(SORT_BLOCK);
    let hist = pool.get(s.ctx, &format!("{label}.hist"), u64::from(num_blocks) * 16 * 4);
    let mut passes: Vec<(u32, u32)> = (0..8).map(|d| (d * 4, 0)).collect();
    passes.extend((0..tile_bits.div_ceil(4)).map(|d| (d * 4, 1)));
    let (mut src, mut dst) = (keys.clone(), alt);
    for (shift, use_hi) in passes {
        let params = SortParams { count, shift, use_hi, num_blocks };
        let block = gpu::params(s.ctx, "trgs.sort.params", &params);
        let count_k = &s.kernels.sort_count;
        let bind = count_k.bind(
            s.ctx,
            &[
                block.as_entire_binding(),
                src.hi.as_entire_binding(),
                src.lo.as_entire_binding(),
                hist.as_entire_binding(),
            ],
        );
        rec.dispatch("sort", count_k, &bind, grid_1d(num_blocks));
        prefix_sum::record(s, rec, pool, &format!("{label}.hist_scan"), &hist, num_blocks * 16);
        let scatter = &s.kernels.sort_scatter;
        let bind = scatter.bind(
            s.ctx,
            &[
                block.as_entire_binding(),
                src.hi.as_entire_binding(),
                src.lo.as_entire_binding(),
                src.values.as_entire_binding(),
                hist.as_entire_binding(),
                dst.hi.as_entire_binding(),
                dst.lo.as_entire_binding(),
                dst.values.as_entire_binding(),
            ],
        );
        rec.dispatch("sort", scatter, &bind, grid_1d(num_blocks));
        std::mem::swap(&mut src, &mut dst);
    }
    src
}
