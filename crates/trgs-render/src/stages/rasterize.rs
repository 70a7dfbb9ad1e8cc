//! Stage `rasterize`, pass 1 (shaders/render/rasterize.wgsl; twin
//! `trgs_core::reference::rasterize`).
use super::Stage;
use crate::gpu::{self, Recorder};
use crate::layout::RasterParams;
use crate::toolkit::paged::Paged;
use trgs_core::pipeline::{TILE_SIZE, TileGrid};

// shaders/render/rasterize.wgsl gives eight consecutive threads a 4 x 2 block of pixels of
// the tile.
const _: () =
    assert!(TILE_SIZE.is_multiple_of(4), "rasterize.wgsl tiles rows in blocks of 4 x 2 pixels");
// shaders/shared/block_walk.wgsl keeps a batch's reaching entries as a 64-bit mask.
const _: () = assert!(TILE_SIZE * TILE_SIZE <= 64, "a batch of TILE_PIXELS entries fits 64 bits");

/// Pass 1's output buffers.
#[derive(Clone, Debug)]
pub struct Pass1Outputs<'a> {
    /// (C_t, 1 - T_t) per pixel.
    pub transmission: &'a wgpu::Buffer,
    /// (D_t, V, M, 0) per pixel.
    pub geometry: &'a wgpu::Buffer,
    /// `RasterState` per pixel.
    pub states: &'a wgpu::Buffer,
}

/// Whether a rasterize pass (or its adjoint) over `projected` and `values` runs its `_paged`
/// variant: when either has a second page.
pub fn is_paged(projected: &Paged, values: &Paged) -> bool {
    projected.is_paged() || values.is_paged()
}

/// The parameter block of pass 1 (and of its adjoint) over the whole of `grid`.
pub fn params(grid: &TileGrid, background: [f32; 3]) -> RasterParams {
    RasterParams {
        width: grid.width,
        height: grid.height,
        tiles_x: grid.tiles_x,
        tiles_y: grid.tiles_y,
        // Pass 1 is view 0: its tiles are the first of the sorted list, numbered as the grid's.
        tile_base: 0,
        tiles_w: grid.tiles_x,
        background: [background[0], background[1], background[2], 0.0],
        ..Default::default()
    }
}

pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    grid: &TileGrid,
    background: [f32; 3],
    depth_variance: bool,
    projected: &Paged,
    values: &Paged,
    ranges: &wgpu::Buffer,
    out: &Pass1Outputs<'_>,
) {
    let p = RasterParams {
        page: projected.first_page_len(),
        key_page: values.first_page_len(),
        ..params(grid, background)
    };
    let block = gpu::params(s.ctx, "trgs.rasterize.params", &p);
    let paged = is_paged(projected, values);
    let k = match (depth_variance, paged) {
        (false, false) => &s.kernels.rasterize,
        (true, false) => &s.kernels.rasterize_depth_variance,
        (false, true) => &s.kernels.rasterize_paged,
        (true, true) => &s.kernels.rasterize_depth_variance_paged,
    };
    let mut entries = vec![
        block.as_entire_binding(),
        projected.first_page(),
        values.first_page(),
        ranges.as_entire_binding(),
        out.transmission.as_entire_binding(),
        out.geometry.as_entire_binding(),
        out.states.as_entire_binding(),
    ];
    if paged {
        entries.extend([projected.second_page_or_first(), values.second_page_or_first()]);
    }
    let bind = k.bind(s.ctx, &entries);
    rec.dispatch("rasterize", k, &bind, [grid.tiles_x, grid.tiles_y, 1]);
}
