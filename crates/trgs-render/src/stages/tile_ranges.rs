//! Stage `tile_ranges` (shaders/tile_ranges.wgsl; twin `trgs_core::reference::tile_ranges`).
use super::Stage;
use crate::gpu::{self, Recorder, grid_1d};
use crate::layout::ScanParams;

/// Write each tile's (start, end) in the sorted keys into `ranges` (cleared first).
pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    sorted_tiles: &wgpu::Buffer,
    count: u32,
    ranges: &wgpu::Buffer,
) {
    rec.encoder.clear_buffer(ranges, 0, None);
    let k = &s.kernels.tile_ranges;
    let block =
        gpu::params(s.ctx, "trgs.tile_ranges.params", &ScanParams { count, ..Default::default() });
    let bind = k.bind(
        s.ctx,
        &[block.as_entire_binding(), sorted_tiles.as_entire_binding(), ranges.as_entire_binding()],
    );
    rec.dispatch("tile_ranges", k, &bind, grid_1d(count.div_ceil(256)));
}
