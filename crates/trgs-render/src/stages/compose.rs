//! Stage `compose` (shaders/render/compose.wgsl; twin `trgs_core::reference::compose`).
use super::Stage;
use crate::gpu::{self, Recorder};
use crate::layout::{ComposeParams, PlaneGpu};
use trgs_core::pipeline::{ReflectionModel, TILE_SIZE, TileGrid, TileRect};
use trgs_core::scene::{Camera, ReflectionPlane};

/// Compose's output buffers.
#[derive(Clone, Debug)]
pub struct ComposeOutputs<'a> {
    pub color: &'a wgpu::Buffer,
    pub reflection: &'a wgpu::Buffer,
    pub strength: &'a wgpu::Buffer,
    pub hit: &'a wgpu::Buffer,
}

/// The planes as compose sees them; `has_pass[k]` says whether plane k's mirrored pass ran.
pub fn planes_gpu(planes: &[ReflectionPlane], has_pass: &[bool]) -> Vec<PlaneGpu> {
    let v4 = |v: glam::DVec3, w: f64| [v.x as f32, v.y as f32, v.z as f32, w as f32];
    planes
        .iter()
        .zip(has_pass)
        .map(|(p, &ran)| PlaneGpu {
            centre: v4(p.centre, p.r0()),
            normal: v4(p.unit_normal(), if ran { 1.0 } else { 0.0 }),
            axis: v4(p.axis, 0.5 * p.width),
            bitangent: v4(p.bitangent(), 0.5 * p.height),
        })
        .collect()
}

/// The camera's pixel rays and the planes, as `compose` and `rasterize_reflection` read them.
#[derive(Debug)]
pub struct RayBuffers {
    pub camera: wgpu::Buffer,
    pub planes: wgpu::Buffer,
}

impl RayBuffers {
    pub fn new(s: Stage<'_>, camera: &Camera, planes: &[PlaneGpu], model: ReflectionModel) -> Self {
        let k = &camera.intrinsics;
        let to_world = camera.pose.rotation.transpose();
        let v4 = |v: glam::DVec3| [v.x as f32, v.y as f32, v.z as f32, 0.0];
        let params = ComposeParams {
            width: k.width,
            height: k.height,
            num_planes: planes.len() as u32,
            model: crate::layout::model_bits(model),
            focal: [k.fx as f32, k.fy as f32, k.cx as f32, k.cy as f32],
            origin: v4(camera.pose.centre()),
            cam_col0: v4(to_world.x_axis),
            cam_col1: v4(to_world.y_axis),
            cam_col2: v4(to_world.z_axis),
        };
        Self {
            camera: gpu::params(s.ctx, "trgs.compose.params", &params),
            planes: gpu::storage_init(s.ctx, "trgs.compose.planes", planes),
        }
    }
}

/// The pixels of `footprint` (a tile rectangle of `grid`): (x0, y0, x1, y1).
fn pixel_area(grid: &TileGrid, footprint: &TileRect) -> [u32; 4] {
    [
        footprint.x0 * TILE_SIZE,
        footprint.y0 * TILE_SIZE,
        (footprint.x1 * TILE_SIZE).min(grid.width),
        (footprint.y1 * TILE_SIZE).min(grid.height),
    ]
}

/// Compose over each of `footprints` (the mirrored passes'); every other pixel gets C = C_t,
/// and zero reflection, strength and hit, by a copy and clears (skipped when one footprint
/// covers the image).
#[allow(clippy::too_many_arguments)]
pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    grid: &TileGrid,
    footprints: &[TileRect],
    rays: &RayBuffers,
    transmission: &wgpu::Buffer,
    geometry: &wgpu::Buffer,
    reflection_raw: &wgpu::Buffer,
    out: &ComposeOutputs<'_>,
) {
    let pixels = u64::from(grid.width) * u64::from(grid.height);
    let whole = [0, 0, grid.width, grid.height];
    let areas: Vec<[u32; 4]> =
        footprints.iter().filter(|f| !f.is_empty()).map(|f| pixel_area(grid, f)).collect();
    if !areas.contains(&whole) {
        rec.encoder.copy_buffer_to_buffer(transmission, 0, out.color, 0, Some(pixels * 16));
        rec.encoder.clear_buffer(out.reflection, 0, Some(pixels * 16));
        rec.encoder.clear_buffer(out.strength, 0, Some(pixels * 16));
        rec.encoder.clear_buffer(out.hit, 0, Some(pixels * 4));
    }
    let kern = &s.kernels.compose;
    for [x0, y0, x1, y1] in areas {
        let area = gpu::storage_init(s.ctx, "trgs.compose.area", &[[x0, y0, x1, y1]]);
        let bind = kern.bind(
            s.ctx,
            &[
                rays.camera.as_entire_binding(),
                rays.planes.as_entire_binding(),
                transmission.as_entire_binding(),
                geometry.as_entire_binding(),
                reflection_raw.as_entire_binding(),
                out.color.as_entire_binding(),
                out.reflection.as_entire_binding(),
                out.strength.as_entire_binding(),
                out.hit.as_entire_binding(),
                area.as_entire_binding(),
            ],
        );
        let groups = [(x1 - x0).div_ceil(16), (y1 - y0).div_ceil(16), 1];
        rec.dispatch("compose", kern, &bind, groups);
    }
}
