//! Stage `rasterize_reflection`, pass 2 (shaders/render/rasterize_reflection.wgsl; twin
//! `trgs_core::reference::rasterize_reflection`): only the tiles of the plane's footprint run, and
//! in them only the pixels whose ray hits the plane's rectangle.
use super::Stage;
use super::compose::RayBuffers;
use crate::gpu::{self, Recorder};
use crate::layout::RasterParams;
use crate::toolkit::paged::Paged;
use trgs_core::pipeline::{TileGrid, TileRect};

/// The parameter block of pass 2 (and of its adjoint): plane slot `slot`, dispatched over the tiles of
/// `footprint`, whose first tile has sorted tile index `tile_base`.
pub fn params(grid: &TileGrid, slot: u32, footprint: &TileRect, tile_base: u32) -> RasterParams {
    RasterParams {
        tile_x0: footprint.x0,
        tile_y0: footprint.y0,
        slot,
        tile_base,
        tiles_w: footprint.x1 - footprint.x0,
        ..super::rasterize::params(grid, [0.0; 3])
    }
}

pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    grid: &TileGrid,
    slot: u32,
    footprint: &TileRect,
    tile_base: u32,
    projected: &Paged,
    values: &Paged,
    ranges: &wgpu::Buffer,
    reflection_raw: &wgpu::Buffer,
    states: &wgpu::Buffer,
    rays: &RayBuffers,
) {
    if footprint.is_empty() {
        return;
    }
    let block = gpu::params(
        s.ctx,
        "trgs.rasterize_reflection.params",
        &RasterParams {
            page: projected.first_page_len(),
            key_page: values.first_page_len(),
            ..params(grid, slot, footprint, tile_base)
        },
    );
    let paged = super::rasterize::is_paged(projected, values);
    let k =
        if paged { &s.kernels.rasterize_reflection_paged } else { &s.kernels.rasterize_reflection };
    let mut entries = vec![
        block.as_entire_binding(),
        projected.first_page(),
        values.first_page(),
        ranges.as_entire_binding(),
        reflection_raw.as_entire_binding(),
        states.as_entire_binding(),
        rays.camera.as_entire_binding(),
        rays.planes.as_entire_binding(),
    ];
    if paged {
        entries.extend([projected.second_page_or_first(), values.second_page_or_first()]);
    }
    let bind = k.bind(s.ctx, &entries);
    let groups = [footprint.x1 - footprint.x0, footprint.y1 - footprint.y0, 1];
    rec.dispatch("rasterize_reflection", k, &bind, groups);
}
