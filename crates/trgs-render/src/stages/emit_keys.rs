//! Stage `emit_keys` (shaders/render/emit_keys.wgsl; twin `trgs_core::reference::emit_keys`):
//! every view's keys at once, entry by entry of the depth order.
use super::sort::KeyList;
use super::tile_counts::DepthEntries;
use super::{ItemCount, Stage};
use crate::gpu::{self, Recorder, strided_grid};
use crate::layout::{EmitParams, ViewTiles};
use crate::toolkit::paged::Paged;

/// Where the keys go besides the list: the scan's `total` of every view's keys, and `kept`, into
/// whose first word emit_keys writes min(total, the list's capacity), the count the sort and
/// tile_ranges cover when it is known on the GPU only, and into its second whether the list
/// dropped keys (1) or not (0).
pub struct KeyCounts<'a> {
    pub total: &'a wgpu::Buffer,
    pub kept: &'a wgpu::Buffer,
}

/// Write the keys (tile indices) and values (Gaussian indices) of the `entries` first entries
/// of `order` into `keys`, at most `capacity` pairs; `offsets` is the scan of their tile counts,
/// `views` numbers each view's tiles in the shared list. `order` is one page; `keys` may have
/// two. `params` gives the scene's Gaussians; the rest of it is filled in here.
#[allow(clippy::too_many_arguments)]
pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    params: &EmitParams,
    entries_count: ItemCount<'_>,
    capacity: u32,
    order: &Paged,
    entries: &DepthEntries,
    offsets: &wgpu::Buffer,
    views: &[ViewTiles],
    keys: &KeyList,
    counts: &KeyCounts<'_>,
) {
    // Always dispatched, if only to write `kept`.
    let most = s.ctx.capabilities.strided_groups;
    let groups = strided_grid(entries_count.capacity().div_ceil(256), most);
    let k = if keys.is_paged() { &s.kernels.emit_keys_paged } else { &s.kernels.emit_keys };
    let params = EmitParams {
        entries: entries_count.capacity(),
        page: keys.first_page_len(),
        capacity,
        ..*params
    };
    let block = gpu::params(s.ctx, "trgs.emit_keys.params", &params);
    // EmitParams::entries is the block's first word.
    entries_count.write_into(rec, &block);
    let table = gpu::storage_init(s.ctx, "trgs.emit_keys.views", views);
    let mut bindings = vec![
        block.as_entire_binding(),
        order.first_page(),
        entries.rects.as_entire_binding(),
        offsets.as_entire_binding(),
        table.as_entire_binding(),
        keys.keys.first_page(),
        keys.values.first_page(),
        counts.total.as_entire_binding(),
        counts.kept.as_entire_binding(),
    ];
    bindings.extend(keys.keys.second_page());
    bindings.extend(keys.values.second_page());
    let bind = k.bind(s.ctx, &bindings);
    rec.dispatch("emit_keys", k, &bind, groups);
}
