//! Stage `display` (shaders/render/display.wgsl; twin `trgs_core::reference::display`).
use super::Stage;
use crate::gpu::{self, Recorder};
use crate::layout::DisplayParams;
use trgs_core::pipeline::DisplayMapping;

/// Record the conversion of `layer` (one vec4 per pixel, `width x height`) into `rgba`, one
/// packed pixel per word and `row_pixels` words per row.
pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    (width, height, row_pixels): (u32, u32, u32),
    mapping: DisplayMapping,
    layer: &wgpu::Buffer,
    rgba: &wgpu::Buffer,
) {
    let (mode, channel, near, far) = mapping.gpu_fields();
    let params = DisplayParams { width, height, row_pixels, mode, channel, near, far, _pad: 0 };
    let params = gpu::params(s.ctx, "trgs.display.params", &params);
    let kern = &s.kernels.display;
    let bind = kern.bind(
        s.ctx,
        &[params.as_entire_binding(), layer.as_entire_binding(), rgba.as_entire_binding()],
    );
    rec.dispatch("display", kern, &bind, [width.div_ceil(16), height.div_ceil(16), 1]);
}
