//! Stage `compose_bwd` (shaders/backward/compose_bwd.wgsl; twin
//! `trgs_core::reference::compose_bwd`): the adjoint of `compose`. Adds the composition's
//! gradients into the pass-layer gradient buffers in place and sums each plane's dL/dR0 and
//! dL/d(unit normal) into `plane_grads` ([`crate::layout::PLANE_GRAD_FLOATS`] per plane).
use super::Stage;
use super::compose::RayBuffers;
use crate::frame::LayerBuffers;
use crate::gpu::Recorder;
use crate::layer_grads::LayerGrads;
use trgs_core::pipeline::TileGrid;

pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    grid: &TileGrid,
    rays: &RayBuffers,
    layers: &LayerBuffers,
    grads: &LayerGrads,
    plane_grads: &wgpu::Buffer,
) {
    let k = &s.kernels.compose_bwd;
    let bind = k.bind(
        s.ctx,
        &[
            rays.camera.as_entire_binding(),
            rays.planes.as_entire_binding(),
            layers.transmission.as_entire_binding(),
            layers.geometry.as_entire_binding(),
            layers.reflection_raw.as_entire_binding(),
            layers.strength.as_entire_binding(),
            layers.hit.as_entire_binding(),
            grads.color.as_entire_binding(),
            grads.reflection.as_entire_binding(),
            grads.strength.as_entire_binding(),
            grads.transmission.as_entire_binding(),
            grads.geometry.as_entire_binding(),
            grads.reflection_raw.as_entire_binding(),
            plane_grads.as_entire_binding(),
        ],
    );
    rec.dispatch("compose_bwd", k, &bind, [grid.width.div_ceil(16), grid.height.div_ceil(16), 1]);
}
