//! Stage `footprint`: the screen tiles a plane's rectangle covers, dilated by one pixel (the
//! gradient-conflict loss's Sobel reads one pixel beyond it). The mirrored pass rasterises only
//! these tiles. It is a handful of vertices per plane, computed on the CPU for the GPU too.
use crate::pipeline::{TILE_SIZE, TileGrid, TileRect};
use crate::scene::{Intrinsics, Pose, ReflectionPlane};
use glam::DVec3;

/// Dilation of the footprint in pixels.
const DILATION_PX: f64 = 1.0;
/// Camera-space depth at which the rectangle is clipped before projection; points of the
/// rectangle closer than this can only be hit by rays near the image border, which the clipped
/// polygon's (huge) projection still covers.
const CLIP_Z: f64 = 1e-9;

/// Tiles covered by the plane's rectangle seen from `pose`, or None when the camera is not on the
/// plane's front side or the rectangle is entirely behind the camera or off screen.
pub fn footprint(
    plane: &ReflectionPlane,
    pose: &Pose,
    k: &Intrinsics,
    grid: &TileGrid,
) -> Option<TileRect> {
    if !(plane.signed_distance(pose.centre()) > 0.0) {
        return None;
    }
    let cam: Vec<DVec3> = plane.corners().iter().map(|&c| pose.transform_point(c)).collect();
    // Clip the polygon against z >= CLIP_Z (Sutherland-Hodgman with one plane).
    let mut poly = Vec::with_capacity(8);
    for i in 0..cam.len() {
        let (a, b) = (cam[i], cam[(i + 1) % cam.len()]);
        let (ia, ib) = (a.z >= CLIP_Z, b.z >= CLIP_Z);
        if ia {
            poly.push(a);
        }
        if ia != ib {
            let s = (CLIP_Z - a.z) / (b.z - a.z);
            poly.push(a + s * (b - a));
        }
    }
    if poly.is_empty() {
        return None;
    }
    let (mut umin, mut vmin, mut umax, mut vmax) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for p in &poly {
        let (u, v) = (k.fx * p.x / p.z + k.cx, k.fy * p.y / p.z + k.cy);
        umin = umin.min(u);
        umax = umax.max(u);
        vmin = vmin.min(v);
        vmax = vmax.max(v);
    }
    // Pixels whose centres (p + 0.5) fall in the dilated box.
    let span = |lo: f64, hi: f64, size: u32| -> Option<(u32, u32)> {
        let a = (lo - DILATION_PX - 0.5).ceil();
        let b = (hi + DILATION_PX - 0.5).floor();
        let max = f64::from(size - 1);
        if !(a <= b && b >= 0.0 && a <= max) {
            return None;
        }
        Some((a.max(0.0) as u32, b.min(max) as u32))
    };
    let (x0, x1) = span(umin, umax, grid.width)?;
    let (y0, y1) = span(vmin, vmax, grid.height)?;
    Some(TileRect {
        x0: x0 / TILE_SIZE,
        y0: y0 / TILE_SIZE,
        x1: x1 / TILE_SIZE + 1,
        y1: y1 / TILE_SIZE + 1,
    })
}
