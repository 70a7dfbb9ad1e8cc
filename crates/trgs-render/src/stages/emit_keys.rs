//! Stage `emit_keys` (shaders/emit_keys.wgsl; twin `trgs_core::reference::emit_keys`): every
//! view's keys at once, entry by entry of the depth order.
use super::Stage;
use super::sort::KeyList;
use super::tile_counts::DepthEntries;
use crate::gpu::{self, Recorder, grid_1d};
use crate::layout::{EmitParams, ViewTiles};

/// Write the keys (tile indices) and values (Gaussian indices) of the first `params.entries`
/// entries of `order` into `keys`; `offsets` is the scan of their tile counts, `views` numbers
/// each view's tiles in the shared list.
#[allow(clippy::too_many_arguments)]
pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    params: &EmitParams,
    order: &wgpu::Buffer,
    entries: &DepthEntries,
    offsets: &wgpu::Buffer,
    views: &[ViewTiles],
    keys: &KeyList,
) {
    if params.entries == 0 {
        return;
    }
    let k = &s.kernels.emit_keys;
    let block = gpu::params(s.ctx, "trgs.emit_keys.params", params);
    let table = gpu::storage_init(s.ctx, "trgs.emit_keys.views", views);
    let bind = k.bind(
        s.ctx,
        &[
            block.as_entire_binding(),
            order.as_entire_binding(),
            entries.rects.as_entire_binding(),
            offsets.as_entire_binding(),
            table.as_entire_binding(),
            keys.keys.as_entire_binding(),
            keys.values.as_entire_binding(),
        ],
    );
    rec.dispatch("emit_keys", k, &bind, grid_1d(params.entries.div_ceil(256)));
}
