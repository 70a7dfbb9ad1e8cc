//! The forward pipeline of one view: validate -> project -> tile_counts -> depth_order ->
//! prefix_sum -> emit_keys -> sort -> tile_ranges -> rasterize; per plane in front of the camera: footprint and
//! the same geometry stages with the mirrored camera -> rasterize_reflection; then compose.
use super::compose::compose;
use super::depth_order::depth_order;
use super::emit_keys::emit_keys;
use super::footprint::footprint;
use super::frame::{Frame, PlaneLayers, ViewPass};
use super::prefix_sum::prefix_sum;
use super::project::{ProjectionFilter, project};
use super::rasterize::rasterize;
use super::rasterize_reflection::rasterize_reflection;
use super::sort::sort_keys;
use super::tile_counts::tile_counts;
use super::tile_ranges::tile_ranges;
use crate::pipeline::{RenderSettings, TileGrid, TileRect, check_render_settings};
use crate::plane_math::mirrored_view;
use crate::scene::{
    Camera, Gaussians, Intrinsics, InvalidInput, ReflectionPlane, ViewTransform, validate_scene,
};

/// Project and bin the Gaussians for one view, restricted to the tiles of `limit`.
pub fn render_view(
    g: &Gaussians<f64>,
    view: &ViewTransform,
    k: &Intrinsics,
    filter: ProjectionFilter<'_>,
    limit: &TileRect,
    near: f64,
) -> ViewPass {
    let grid = TileGrid::new(k.width, k.height);
    let projected = project(g, view, k, filter, limit, near);
    let counts = tile_counts(&projected, &grid, limit);
    let order = depth_order(&projected, &counts, near);
    let ordered: Vec<u32> = order.iter().map(|&i| counts[i as usize]).collect();
    let (offsets, total) = prefix_sum(&ordered);
    let (mut keys, mut values) = emit_keys(&projected, &grid, limit, &order, &offsets, total);
    sort_keys(&mut keys, &mut values);
    let ranges = tile_ranges(&keys, grid.tile_count());
    ViewPass { view: *view, projected, keys, values, ranges }
}

/// Render every layer of `camera`'s view. Non-finite or malformed input (Gaussians, planes,
/// camera, settings) is rejected with what is wrong named, before any work.
pub fn render(
    g: &Gaussians<f64>,
    planes: &[ReflectionPlane],
    camera: &Camera,
    settings: &RenderSettings,
) -> Result<Frame, InvalidInput> {
    validate_scene(g, planes, camera)?;
    check_render_settings(settings.background, settings.near)?;
    let k = &camera.intrinsics;
    let grid = TileGrid::new(k.width, k.height);
    let view = ViewTransform::from(&camera.pose);
    let primary = render_view(g, &view, k, ProjectionFilter::All, &grid.full(), settings.near);
    let pass1 =
        rasterize(&primary.projected, &primary.values, &primary.ranges, &grid, settings.background);

    let mut plane_layers = Vec::with_capacity(planes.len());
    for plane in planes {
        let layers = footprint(plane, &camera.pose, k, &grid).map(|fp| {
            let mview = mirrored_view(plane, &view);
            let pass =
                render_view(g, &mview, k, ProjectionFilter::FrontOf(plane), &fp, settings.near);
            let out = rasterize_reflection(
                &pass.projected,
                &pass.values,
                &pass.ranges,
                &grid,
                &fp,
                camera,
                plane,
            );
            PlaneLayers {
                raw_color: out.raw_color,
                intensity: out.intensity,
                footprint: fp,
                pass,
                pixels: out.pixels,
            }
        });
        plane_layers.push(layers);
    }
    let raw: Vec<_> = plane_layers.iter().map(|p| p.as_ref().map(|p| &p.raw_color)).collect();
    let int: Vec<_> = plane_layers.iter().map(|p| p.as_ref().map(|p| &p.intensity)).collect();
    let composed =
        compose(camera, planes, &pass1.transmission, &pass1.mask, &raw, &int, settings.reflection);
    Ok(Frame {
        color: composed.color,
        transmission: pass1.transmission,
        depth: pass1.depth,
        depth_variance: pass1.depth_variance,
        mask: pass1.mask,
        alpha: pass1.alpha,
        hit: composed.hit,
        strength_raw: composed.strength_raw,
        strength: composed.strength,
        reflection: composed.reflection,
        planes: plane_layers,
        primary,
        pixels: pass1.pixels,
    })
}
