//! Stage `tile_counts` (shaders/render/tile_counts.wgsl; twin
//! `trgs_core::reference::tile_counts`): the tiles each Gaussian of a view touches; the touching
//! ones become entries of the frame's depth order (see [`DepthEntries`]).
use super::Stage;
use super::project::{Candidates, WORK_STRIDE};
use crate::gpu::{self, BufferPool, Recorder, range};
use crate::layout::TileParams;
use crate::scene::GpuScene;
use crate::toolkit::paged::Paged;
use trgs_core::pipeline::{TileGrid, TileRect, depth_key_base};

/// The parameter block of a view's binning, limited to `limit` (a footprint, or the whole grid).
pub fn params(grid: &TileGrid, limit: &TileRect, near: f64) -> TileParams {
    TileParams {
        depth_base: depth_key_base(near),
        width: grid.width,
        height: grid.height,
        tiles_x: grid.tiles_x,
        tiles_y: grid.tiles_y,
        limit: [limit.x0, limit.y0, limit.x1, limit.y1],
        ..Default::default()
    }
}

/// What `tile_counts` keeps per entry of the frame's depth order (one entry per view and
/// Gaussian, `view * gaussians + index`) for `depth_order` and `emit_keys`.
#[derive(Clone, Debug)]
pub struct DepthEntries {
    /// A bit per entry, set when the Gaussian touches a tile of the view: entry e is bit
    /// e % 32 of word e / 32 (`present_words` words). A bit mask keeps the scan and compaction
    /// that list the entries 32 times shorter than the capacity.
    pub present: wgpu::Buffer,
    pub present_words: u32,
    /// Per entry: the f32 bits of its depth.
    pub depths: wgpu::Buffer,
    /// Per entry: the tile rectangle, two u32 (x0 | y0 << 16, x1 | y1 << 16).
    pub rects: wgpu::Buffer,
    /// Per view: its key total, two u32: the low 32 bits and the carries out of them.
    pub key_totals: wgpu::Buffer,
    /// Entries: views x Gaussians.
    pub capacity: u32,
}

impl DepthEntries {
    /// Buffers for `views` views of `gaussians` Gaussians, flags and totals cleared.
    pub fn new(
        s: Stage<'_>,
        rec: &mut Recorder,
        pool: &mut BufferPool,
        views: usize,
        gaussians: u32,
    ) -> Self {
        let capacity = views as u32 * gaussians;
        let bytes = u64::from(capacity.max(1)) * 4;
        let present_words = capacity.div_ceil(32);
        let present_bytes = u64::from(present_words.max(1)) * 4;
        let present = pool.get(s.ctx, "trgs.tile_counts.present", present_bytes);
        let depths = pool.get(s.ctx, "trgs.tile_counts.depths", bytes);
        let rects = pool.get(s.ctx, "trgs.tile_counts.rects", bytes * 2);
        let key_totals = pool.get(s.ctx, "trgs.tile_counts.key_totals", views as u64 * 8);
        rec.encoder.clear_buffer(&present, 0, None);
        rec.encoder.clear_buffer(&key_totals, 0, None);
        Self { present, present_words, depths, rects, key_totals, capacity }
    }
}

#[allow(clippy::too_many_arguments)]
pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    scene: &GpuScene,
    base: &TileParams,
    projected: &Paged,
    candidates: &Candidates,
    counts: &wgpu::Buffer,
    entries: &DepthEntries,
) {
    let k = &s.kernels.tile_counts;
    rec.encoder.clear_buffer(counts, 0, None);
    for (chunk, (first, count)) in scene.chunks().into_iter().enumerate() {
        let [list, work] = candidates.chunk(chunk, first, count);
        let p = TileParams { count, first, ..*base };
        let block = gpu::params(s.ctx, "trgs.tile_counts.params", &p);
        let (f, c) = (u64::from(first), u64::from(count));
        let bind = k.bind(
            s.ctx,
            &[
                block.as_entire_binding(),
                projected.range(first, count),
                range(counts, f * 4, c * 4),
                list,
                work,
                entries.rects.as_entire_binding(),
                entries.depths.as_entire_binding(),
                entries.present.as_entire_binding(),
                entries.key_totals.as_entire_binding(),
            ],
        );
        let at = chunk as u64 * WORK_STRIDE;
        rec.dispatch_indirect("tile_counts", k, &bind, &candidates.work, at);
    }
}
