//! The forward pipeline of one view: validate -> project -> tile_counts -> depth_order ->
//! prefix_sum -> emit_keys -> sort -> tile_ranges -> rasterize; per plane in front of the camera: footprint and
//! the same geometry stages with the mirrored camera -> rasterize_reflection; then compose.
use super::compose::{ReflectionModel, compose};
use super::frame::{Frame, PlaneLayers};
use super::{
    Projected, ProjectionFilter, TileGrid, TileRect, depth_order, emit_keys, footprint, prefix_sum,
    project, rasterize, rasterize_reflection, sort_keys, tile_counts, tile_ranges,
};
use crate::plane_math::mirrored_view;
use crate::scene::{
    Camera, Gaussians, Intrinsics, InvalidInput, ReflectionPlane, ViewTransform, validate_scene,
};

/// Settings of the reference renderer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    /// Gaussians with a camera-space depth below this are culled (0.2 as in 3DGS).
    pub near: f64,
    /// Colour behind the last transmittance of C_t.
    pub background: [f64; 3],
    /// The reflection model's switches (the full model by default).
    pub reflection: ReflectionModel,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self { near: 0.2, background: [0.0; 3], reflection: ReflectionModel::default() }
    }
}

/// The geometry stages of one view: projection and the sorted per-tile lists.
#[derive(Clone, Debug)]
pub struct ViewPass {
    pub view: ViewTransform,
    pub projected: Projected,
    /// Sorted tile indices, one per key.
    pub keys: Vec<u32>,
    pub values: Vec<u32>,
    pub ranges: Vec<(u32, u32)>,
}

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

/// Settings no frame can be made with, refused by the twin and the GPU renderer alike: a
/// non-finite background (every pixel would be NaN), a near plane that is not a positive finite
/// depth (at or behind the camera the projection divides by zero or draws what is behind it).
pub fn check_render_settings(background: [f64; 3], near: f64) -> Result<(), InvalidInput> {
    if !background.iter().all(|c| c.is_finite()) {
        let problem = format!("background {background:?} must be finite");
        return Err(InvalidInput::Setting { what: "background", problem });
    }
    if !(near > 0.0 && near.is_finite()) {
        let problem = format!("near {near} must be a positive finite depth");
        return Err(InvalidInput::Setting { what: "near", problem });
    }
    Ok(())
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
