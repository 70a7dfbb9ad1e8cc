//! Stage `rasterize_reflection_bwd` (shaders/rasterize_reflection_bwd.wgsl; twin
//! `trgs_core::reference::rasterize_reflection_bwd`): the adjoint of pass 2 over the plane's
//! footprint, from dL/d(C_raw, A) to each mirrored Gaussian's screen-space gradients.
use super::Stage;
use super::rasterize_bwd::ViewLists;
use crate::frame::LayerBuffers;
use crate::gpu::{self, Recorder};
use crate::layer_grads::LayerGrads;
use trgs_core::reference::{TileGrid, TileRect};

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
    projected_grads: &wgpu::Buffer,
) {
    if footprint.is_empty() {
        return;
    }
    let params = super::rasterize_reflection::params(grid, slot, footprint, tile_base);
    let block = gpu::params(s.ctx, "trgs.rasterize_reflection_bwd.params", &params);
    let k = &s.kernels.rasterize_reflection_bwd;
    let bind = k.bind(
        s.ctx,
        &[
            block.as_entire_binding(),
            lists.projected.as_entire_binding(),
            lists.values.as_entire_binding(),
            lists.ranges.as_entire_binding(),
            layers.reflection_states.as_entire_binding(),
            grads.reflection_raw.as_entire_binding(),
            projected_grads.as_entire_binding(),
        ],
    );
    let groups = [footprint.x1 - footprint.x0, footprint.y1 - footprint.y0, 1];
    rec.dispatch("rasterize_reflection_bwd", k, &bind, groups);
}
