//! Stage `rasterize_reflection_bwd` (shaders/backward/rasterize_reflection_bwd.wgsl; twin
//! `trgs_core::reference::rasterize_reflection_bwd`): the adjoint of pass 2 over the plane's
//! footprint, from dL/d(C_raw, A) to each mirrored Gaussian's screen-space gradients.
use super::Stage;
use super::rasterize_bwd::ViewLists;
use crate::frame::LayerBuffers;
use crate::gpu::{self, Recorder};
use crate::layer_grads::LayerGrads;
use crate::toolkit::paged::Paged;
use trgs_core::pipeline::{TileGrid, TileRect};

#[allow(clippy::too_many_arguments)]
pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    grid: &TileGrid,
    slot: u32,
    footprint: &TileRect,
    tile_base: u32,
    lists: ViewLists<'_>,
    layers: &LayerBuffers,
    grads: &LayerGrads,
    projected_grads: &Paged,
) {
    if footprint.is_empty() {
        return;
    }
    let params = crate::layout::RasterParams {
        page: lists.projected.first_page_len(),
        key_page: lists.values.first_page_len(),
        ..super::rasterize_reflection::params(grid, slot, footprint, tile_base)
    };
    let block = gpu::params(s.ctx, "trgs.rasterize_reflection_bwd.params", &params);
    let paged = super::rasterize::is_paged(lists.projected, lists.values);
    let k = if paged {
        &s.kernels.rasterize_reflection_bwd_paged
    } else {
        &s.kernels.rasterize_reflection_bwd
    };
    let mut entries = vec![
        block.as_entire_binding(),
        lists.projected.first_page(),
        lists.values.first_page(),
        lists.ranges.as_entire_binding(),
        layers.reflection_states.as_entire_binding(),
        grads.reflection_raw.as_entire_binding(),
        projected_grads.first_page(),
    ];
    let spare = lists.spare_grads_page(s, paged, projected_grads);
    if paged {
        entries.extend(lists.paged_tail(projected_grads, spare.as_ref()));
    }
    let bind = k.bind(s.ctx, &entries);
    let groups = [footprint.x1 - footprint.x0, footprint.y1 - footprint.y0, 1];
    rec.dispatch("rasterize_reflection_bwd", k, &bind, groups);
}
