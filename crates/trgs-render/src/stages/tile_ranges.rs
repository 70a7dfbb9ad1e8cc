//! Stage `tile_ranges` (shaders/render/tile_ranges.wgsl; twin `trgs_core::reference::tile_ranges`).
use super::{ItemCount, Stage};
use crate::gpu::{self, Recorder, strided_grid};
use crate::layout::ScanParams;
use crate::toolkit::paged::Paged;

/// Write each tile's (start, end) among the `count` first sorted keys into `ranges` (cleared
/// first).
pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    sorted_tiles: &Paged,
    count: ItemCount<'_>,
    ranges: &wgpu::Buffer,
) {
    rec.encoder.clear_buffer(ranges, 0, None);
    let paged = sorted_tiles.is_paged();
    let k = if paged { &s.kernels.tile_ranges_paged } else { &s.kernels.tile_ranges };
    let page = sorted_tiles.first_page_len();
    let most = s.ctx.capabilities.strided_groups;
    let groups = strided_grid(count.capacity().div_ceil(256), most);
    let params = ScanParams { count: count.capacity(), page, ..Default::default() };
    let block = gpu::params(s.ctx, "trgs.tile_ranges.params", &params);
    // ScanParams::count is the block's first word.
    count.write_into(rec, &block);
    let mut bindings =
        vec![block.as_entire_binding(), sorted_tiles.first_page(), ranges.as_entire_binding()];
    bindings.extend(sorted_tiles.second_page());
    let bind = k.bind(s.ctx, &bindings);
    rec.dispatch("tile_ranges", k, &bind, groups);
}
