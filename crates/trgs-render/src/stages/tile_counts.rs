//! Stage `tile_counts` (shaders/tile_counts.wgsl; twin `trgs_core::reference::tile_counts`).
use super::Stage;
use super::project::{Candidates, WORK_STRIDE};
use crate::gpu::{self, Recorder, range};
use crate::layout::{ProjectedGaussian, TileParams};
use crate::scene::GpuScene;
use trgs_core::reference::{TileGrid, TileRect};

const PROJECTED: u64 = std::mem::size_of::<ProjectedGaussian>() as u64;

/// The parameter block of a view's binning, limited to `limit` (a footprint, or the whole grid).
pub fn params(grid: &TileGrid, limit: &TileRect) -> TileParams {
    TileParams {
        width: grid.width,
        height: grid.height,
        tiles_x: grid.tiles_x,
        tiles_y: grid.tiles_y,
        limit: [limit.x0, limit.y0, limit.x1, limit.y1],
        ..Default::default()
    }
}

pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    scene: &GpuScene,
    base: &TileParams,
    projected: &wgpu::Buffer,
    candidates: &Candidates,
    counts: &wgpu::Buffer,
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
                range(projected, f * PROJECTED, c * PROJECTED),
                range(counts, f * 4, c * 4),
                list,
                work,
            ],
        );
        let at = chunk as u64 * WORK_STRIDE;
        rec.dispatch_indirect("tile_counts", k, &bind, &candidates.work, at);
    }
}
