//! The checks before a render touches its frame or records anything: the image, the camera and
//! the settings are valid, and the frame's buffers and dispatches fit the adapter's limits.
use super::options::{RenderError, RenderOptions};
use crate::GpuContext;
use crate::scene::GpuScene;
use crate::toolkit::paged::MAX_PAGES;
use trgs_core::pipeline::TileGrid;
use trgs_core::scene::Camera;

/// Bytes of one projected Gaussian's record.
pub(super) const PROJECTED_BYTES: u64 =
    std::mem::size_of::<crate::layout::ProjectedGaussian>() as u64;

/// The largest per-pixel buffer of a frame with `planes` reflection slots, in bytes per pixel
/// (the layers are bound whole, unlike the scene's attributes, which are bound in chunks).
fn bytes_per_pixel(planes: usize) -> u64 {
    let slots = planes.max(1) as u64;
    let state = std::mem::size_of::<crate::layout::RasterState>() as u64;
    let reflection =
        slots * (16u64).max(std::mem::size_of::<crate::layout::ReflectionState>() as u64);
    state.max(16).max(reflection)
}

/// Fails when a buffer of `bytes` would not fit one binding.
fn check_binding(
    ctx: &GpuContext,
    camera: &Camera,
    what: &'static str,
    bytes: u64,
) -> Result<(), RenderError> {
    let limit = ctx.binding_limit();
    if bytes > limit {
        return Err(RenderError::FrameTooLarge { name: camera.name.clone(), what, bytes, limit });
    }
    Ok(())
}

/// Checks a render of `scene` through `camera`: an image of at least one pixel, a valid camera
/// and settings, no more tiles along an axis than a dispatch has workgroups, and layers and
/// projected records that the adapter can bind. Returns the image's tile grid.
pub(super) fn check_request(
    ctx: &GpuContext,
    scene: &GpuScene,
    camera: &Camera,
    options: &RenderOptions,
) -> Result<TileGrid, RenderError> {
    let k = &camera.intrinsics;
    if k.width == 0 || k.height == 0 {
        return Err(RenderError::EmptyImage {
            name: camera.name.clone(),
            width: k.width,
            height: k.height,
        });
    }
    camera
        .validate()
        .map_err(|source| RenderError::Camera { name: camera.name.clone(), source })?;
    let background = options.background.map(f64::from);
    trgs_core::pipeline::check_render_settings(background, options.near)?;
    let grid = TileGrid::new(k.width, k.height);
    let most = ctx.device.limits().max_compute_workgroups_per_dimension;
    if let Some(tiles) = [grid.tiles_x, grid.tiles_y].into_iter().find(|&t| t > most) {
        return Err(RenderError::TooManyTiles { name: camera.name.clone(), tiles, limit: most });
    }
    let pixels = u64::from(k.width) * u64::from(k.height);
    let planes = scene.planes();
    check_binding(ctx, camera, "image layers", pixels * bytes_per_pixel(planes.len()))?;
    // The rasterize passes bind each view's projected Gaussians whole, in at most MAX_PAGES
    // pages of one binding each.
    let pages = scene.len().div_ceil(scene.page_len());
    if pages > MAX_PAGES {
        return Err(RenderError::FrameTooLarge {
            name: camera.name.clone(),
            what: "projected Gaussians (one record each, in two bindings)",
            bytes: u64::from(scene.len()) * PROJECTED_BYTES,
            limit: u64::from(MAX_PAGES * scene.page_len()) * PROJECTED_BYTES,
        });
    }
    Ok(grid)
}

/// Checks the depth order of `views` views of `gaussians` Gaussians (one entry per view and
/// Gaussian): its entry indices and its tile rectangles.
pub(super) fn check_entries(
    ctx: &GpuContext,
    camera: &Camera,
    views: usize,
    gaussians: u32,
) -> Result<(), RenderError> {
    // Entry indices (view x Gaussian) are u32 (the key totals carry, see tile_counts).
    let capacity = views as u64 * u64::from(gaussians);
    if capacity > u64::from(u32::MAX) {
        return Err(RenderError::FrameTooLarge {
            name: camera.name.clone(),
            what: "depth-order entries (views x Gaussians)",
            bytes: capacity * 4,
            limit: u64::from(u32::MAX) * 4,
        });
    }
    check_binding(ctx, camera, "depth-order tile rectangles", capacity * 8)
}
