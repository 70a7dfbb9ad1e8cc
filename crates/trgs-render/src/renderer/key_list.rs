//! Phase 2 of a render, the key list: every view's keys into one list (a view's tiles numbered
//! after the previous view's: the camera's whole grid, then each footprint), one sort by tile,
//! one pass of tile ranges.
use super::binning::DepthBinning;
use super::job::RenderJob;
use super::key_sizing::KeyListSize;
use crate::frame::{Binning, ViewBuffers};
use crate::gpu::{BufferPool, Recorder};
use crate::layout::{EmitParams, ViewTiles};
use crate::stages::sort::KeyList;
use crate::stages::{ItemCount, emit_keys, sort, tile_ranges};

/// Records the key list of `size` (the module's docs) from the depth order; every view of
/// `views` gets the sorted list and the tile ranges, and the frame keeps the returned binning.
pub(super) fn emit_and_sort(
    rec: &mut Recorder,
    pool: &mut BufferPool,
    job: &RenderJob<'_>,
    depth: DepthBinning,
    views: &mut [ViewBuffers],
    size: &KeyListSize,
) -> Binning {
    let (s, ctx, capacity) = (job.s, job.s.ctx, size.capacity);
    let (tables, tiles) = number_tiles(views);
    let keys = KeyList::from_pool(ctx, pool, "trgs.emit_keys", capacity, job.key_page_len);
    let kept = pool.get(ctx, "trgs.emit_keys.kept", 8);
    let (in_order, held) = match &size.exact {
        Some(t) => (ItemCount::Known(t.entries), ItemCount::Known(capacity)),
        None => (
            ItemCount::OnGpu { counter: &depth.order.entries, capacity: depth.entries.capacity },
            ItemCount::OnGpu { counter: &kept, capacity },
        ),
    };
    let emit = EmitParams { gaussians: job.scene.len(), ..Default::default() };
    let o = &depth.order.list.values;
    let counts = emit_keys::KeyCounts { total: &depth.total, kept: &kept };
    let (entries, offs) = (&depth.entries, &depth.offsets);
    emit_keys::record(s, rec, &emit, in_order, capacity, o, entries, offs, &tables, &keys, &counts);
    let captured_keys =
        job.options.capture_intermediates.then(|| capture_keys(rec, pool, job, &keys, capacity));
    let tile_digits: Vec<_> = sort::digits(sort::bits_below(tiles)).collect();
    let sorted = sort::record(s, rec, "sort", pool, "trgs.sort", &keys, held, &tile_digits);
    let ranges = pool.get(ctx, "trgs.tile_ranges.ranges", u64::from(tiles) * 8);
    tile_ranges::record(s, rec, &sorted.keys, held, &ranges);
    for v in views.iter_mut() {
        v.keys = Some(sorted.clone());
        v.ranges = Some(ranges.clone());
    }
    Binning {
        order: depth.order.list,
        offsets: depth.offsets,
        // A list sized from earlier frames learns these when its totals arrive.
        entries: size.exact.as_ref().map_or(0, |t| t.entries),
        total: if size.exact.is_some() { capacity } else { 0 },
        emitted: captured_keys,
        kept,
    }
}

/// Numbers every view's tiles after the previous view's, row by row within its limit: the
/// tables emit_keys reads, and the tiles of all views.
fn number_tiles(views: &mut [ViewBuffers]) -> (Vec<ViewTiles>, u32) {
    let mut tile_base = 0u32;
    let mut tables = Vec::with_capacity(views.len());
    for v in views.iter_mut() {
        v.tile_base = tile_base;
        tables.push(ViewTiles {
            tile_base,
            x0: v.limit.x0,
            y0: v.limit.y0,
            row: v.limit.x1 - v.limit.x0,
        });
        tile_base += v.limit.count();
    }
    (tables, tile_base)
}

/// A copy of the keys as emitted, before the sort sorts them in place (with
/// `capture_intermediates`).
fn capture_keys(
    rec: &mut Recorder,
    pool: &mut BufferPool,
    job: &RenderJob<'_>,
    keys: &KeyList,
    capacity: u32,
) -> KeyList {
    let copy = KeyList::from_pool(job.s.ctx, pool, "trgs.capture", capacity, job.key_page_len);
    for (from, to) in [(&keys.keys, &copy.keys), (&keys.values, &copy.values)] {
        for (src, dst) in from.pages().iter().zip(to.pages()) {
            rec.encoder.copy_buffer_to_buffer(src, 0, dst, 0, src.size().min(dst.size()));
        }
    }
    copy
}
