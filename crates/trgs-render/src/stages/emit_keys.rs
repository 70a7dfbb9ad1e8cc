//! Stage `emit_keys` (shaders/emit_keys.wgsl; twin `trgs_core::reference::emit_keys`): every
//! view's keys at once, entry by entry of the depth order.
use super::Stage;
use super::sort::KeyList;
use super::tile_counts::DepthEntries;
use crate::gpu::{self, Recorder, grid_1d};
use crate::layout::{EmitParams, ViewTiles};
use crate::toolkit::paged::Paged;

/// Write the keys (tile indices) and values (Gaussian indices) of the first `params.entries`
/// entries of `order` into `keys`; `offsets` is the scan of their tile counts, `views` numbers
/// each view's tiles in the shared list. `order` is one page; `keys` may have two.
#[allow(clippy::too_many_arguments)]
pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    params: &EmitParams,
    order: &Paged,
    entries: &DepthEntries,
    offsets: &wgpu::Buffer,
    views: &[ViewTiles],
    keys: &KeyList,
) {
    if params.entries == 0 {
        return;
    }
    let k = if keys.is_paged() { &s.kernels.emit_keys_paged } else { &s.kernels.emit_keys };
    let params = EmitParams { page: keys.first_page_len(), ..*params };
    let block = gpu::params(s.ctx, "trgs.emit_keys.params", &params);
    let table = gpu::storage_init(s.ctx, "trgs.emit_keys.views", views);
    let mut bindings = vec![
        block.as_entire_binding(),
        order.first_page(),
        entries.rects.as_entire_binding(),
        offsets.as_entire_binding(),
        table.as_entire_binding(),
        keys.keys.first_page(),
        keys.values.first_page(),
    ];
    bindings.extend(keys.keys.second_page());
    bindings.extend(keys.values.second_page());
    let bind = k.bind(s.ctx, &bindings);
    rec.dispatch("emit_keys", k, &bind, grid_1d(params.entries.div_ceil(256)));
}
