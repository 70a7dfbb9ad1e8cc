//! Stage `rasterize_bwd` (shaders/backward/rasterize_bwd.wgsl; twin
//! `trgs_core::reference::rasterize_bwd`): the adjoint of pass 1, from the total gradients of
//! C_t, alpha, D_t, V and M to each Gaussian's screen-space gradients.
use super::Stage;
use crate::frame::LayerBuffers;
use crate::gpu::{self, Recorder};
use crate::layer_grads::LayerGrads;
use crate::layout::RasterParams;
use crate::toolkit::paged::Paged;
use trgs_core::pipeline::TileGrid;

/// The sorted lists of the view being replayed.
#[derive(Clone, Copy, Debug)]
pub struct ViewLists<'a> {
    pub projected: &'a Paged,
    pub values: &'a Paged,
    pub ranges: &'a wgpu::Buffer,
}

impl<'a> ViewLists<'a> {
    /// A `_paged` adjoint that runs for the key values' second page alone binds this in place of
    /// the gradients' second page (a writable binding cannot repeat the first; never indexed).
    pub(crate) fn spare_grads_page(
        &self,
        s: Stage<'_>,
        paged: bool,
        projected_grads: &Paged,
    ) -> Option<wgpu::Buffer> {
        (paged && !projected_grads.is_paged())
            .then(|| gpu::storage(s.ctx, "trgs.rasterize_bwd.spare_page", 16))
    }

    /// What a `_paged` adjoint binds after its own bindings: the second pages of the projected
    /// records, of their gradients (`spare` where they have one page) and of the key values.
    pub(crate) fn paged_tail<'b>(
        &self,
        projected_grads: &'b Paged,
        spare: Option<&'b wgpu::Buffer>,
    ) -> [wgpu::BindingResource<'b>; 3]
    where
        'a: 'b,
    {
        #[allow(clippy::expect_used)]
        let grads_hi = projected_grads
            .second_page()
            .or(spare.map(wgpu::Buffer::as_entire_binding))
            .expect("a spare page where the gradients have one (spare_grads_page)");
        [self.projected.second_page_or_first(), grads_hi, self.values.second_page_or_first()]
    }
}

#[allow(clippy::too_many_arguments)]
pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    grid: &TileGrid,
    background: [f32; 3],
    depth_variance: bool,
    lists: ViewLists<'_>,
    layers: &LayerBuffers,
    grads: &LayerGrads,
    projected_grads: &Paged,
) {
    let params = RasterParams {
        depth_variance: u32::from(depth_variance),
        page: lists.projected.first_page_len(),
        key_page: lists.values.first_page_len(),
        ..super::rasterize::params(grid, background)
    };
    let block = gpu::params(s.ctx, "trgs.rasterize_bwd.params", &params);
    let paged = super::rasterize::is_paged(lists.projected, lists.values);
    let k = if paged { &s.kernels.rasterize_bwd_paged } else { &s.kernels.rasterize_bwd };
    let mut entries = vec![
        block.as_entire_binding(),
        lists.projected.first_page(),
        lists.values.first_page(),
        lists.ranges.as_entire_binding(),
        layers.states.as_entire_binding(),
        layers.geometry.as_entire_binding(),
        grads.transmission.as_entire_binding(),
        grads.geometry.as_entire_binding(),
        projected_grads.first_page(),
    ];
    let spare = lists.spare_grads_page(s, paged, projected_grads);
    if paged {
        entries.extend(lists.paged_tail(projected_grads, spare.as_ref()));
    }
    let bind = k.bind(s.ctx, &entries);
    rec.dispatch("rasterize_bwd", k, &bind, [grid.tiles_x, grid.tiles_y, 1]);
}
