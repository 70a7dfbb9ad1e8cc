//! Stage `tile_counts`: the screen tiles each projected Gaussian touches. The rule is evaluated in
//! f32 exactly as the WGSL stage does it, so that binning matches the GPU bit for bit when both
//! start from the same projected values.
use super::Projected;
use crate::pipeline::{TILE_SIZE, TileGrid, TileRect};
use glam::DVec2;

/// Inclusive range of pixel indices along one axis whose centres (p + 0.5) lie in
/// `[centre - half, centre + half]`, clipped to `[0, size)`; None when empty.
fn pixel_span(centre: f32, half: f32, size: u32) -> Option<(u32, u32)> {
    let lo = (centre - half - 0.5).ceil();
    let hi = (centre + half - 0.5).floor();
    let max = (size - 1) as f32;
    // Written so that NaN falls through to None.
    if !(lo <= hi && hi >= 0.0 && lo <= max) {
        return None;
    }
    Some((lo.max(0.0) as u32, hi.min(max) as u32))
}

/// Tiles of the box `mean2d +- extent` (in f32), intersected with `limit`.
pub fn tile_rect(mean2d: DVec2, extent: DVec2, grid: &TileGrid, limit: &TileRect) -> TileRect {
    let empty = TileRect::default();
    let Some((px0, px1)) = pixel_span(mean2d.x as f32, extent.x as f32, grid.width) else {
        return empty;
    };
    let Some((py0, py1)) = pixel_span(mean2d.y as f32, extent.y as f32, grid.height) else {
        return empty;
    };
    let r = TileRect {
        x0: px0 / TILE_SIZE,
        y0: py0 / TILE_SIZE,
        x1: px1 / TILE_SIZE + 1,
        y1: py1 / TILE_SIZE + 1,
    };
    r.intersect(limit)
}

/// Number of tiles each Gaussian touches (zero when culled).
pub fn tile_counts(p: &Projected, grid: &TileGrid, limit: &TileRect) -> Vec<u32> {
    (0..p.len())
        .map(|i| {
            if p.visible[i] { tile_rect(p.mean2d[i], p.extent[i], grid, limit).count() } else { 0 }
        })
        .collect()
}
