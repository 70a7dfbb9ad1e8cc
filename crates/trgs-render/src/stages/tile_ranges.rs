//! Stage `tile_ranges` (shaders/tile_ranges.wgsl; twin `trgs_core::reference::tile_ranges`).
use super::Stage;
use crate::gpu::{self, Recorder, grid_1d};
use crate::layout::ScanParams;
use crate::toolkit::paged::Paged;

/// Write each tile's (start, end) in the sorted keys into `ranges` (cleared first).
pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    sorted_tiles: &Paged,
    count: u32,
    ranges: &wgpu::Buffer,
) {
    rec.encoder.clear_buffer(ranges, 0, None);
    let paged = sorted_tiles.is_paged();
    let k = if paged { &s.kernels.tile_ranges_paged } else { &s.kernels.tile_ranges };
    let page = sorted_tiles.first_page_len();
    let params = ScanParams { count, page, ..Default::default() };
    let block = gpu::params(s.ctx, "trgs.tile_ranges.params", &params);
    let mut bindings =
        vec![block.as_entire_binding(), sorted_tiles.first_page(), ranges.as_entire_binding()];
    bindings.extend(sorted_tiles.second_page());
    let bind = k.bind(s.ctx, &bindings);
    rec.dispatch("tile_ranges", k, &bind, grid_1d(count.div_ceil(256)));
}
