//! Stage `compose` (shaders/compose.wgsl; twin `trgs_core::reference::compose`).
use super::Stage;
use crate::gpu::{self, Recorder};
use crate::layout::{ComposeParams, PlaneGpu};
use trgs_core::reference::{TILE_SIZE, TileGrid, TileRect};
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
    /// `area`: the pixels compose runs over (`ComposeParams::area`).
    pub fn new(
        s: Stage<'_>,
        camera: &Camera,
        planes: &[PlaneGpu],
        model: trgs_core::reference::ReflectionModel,
        area: [u32; 4],
    ) -> Self {
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
            area,
        };
        Self {
            camera: gpu::params(s.ctx, "trgs.compose.params", &params),
            planes: gpu::storage_init(s.ctx, "trgs.compose.planes", planes),
        }
    }
}

/// The pixels of the union of `footprints` (tile rectangles of `grid`), as `ComposeParams::area`.
pub fn area(grid: &TileGrid, footprints: &[TileRect]) -> [u32; 4] {
    let union = footprints.iter().filter(|r| !r.is_empty()).fold(None, |u: Option<TileRect>, r| {
        Some(u.map_or(*r, |u| TileRect {
            x0: u.x0.min(r.x0),
            y0: u.y0.min(r.y0),
            x1: u.x1.max(r.x1),
            y1: u.y1.max(r.y1),
        }))
    });
    union.map_or([0; 4], |u| {
        [
            u.x0 * TILE_SIZE,
            u.y0 * TILE_SIZE,
            (u.x1 * TILE_SIZE).min(grid.width),
            (u.y1 * TILE_SIZE).min(grid.height),
        ]
    })
}

/// Compose over `area`; every other pixel gets C = C_t, and zero reflection, strength and hit.
pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    area: [u32; 4],
    rays: &RayBuffers,
    transmission: &wgpu::Buffer,
    geometry: &wgpu::Buffer,
    reflection_raw: &wgpu::Buffer,
    out: &ComposeOutputs<'_>,
) {
    rec.encoder.copy_buffer_to_buffer(transmission, 0, out.color, 0, None);
    for b in [out.reflection, out.strength, out.hit] {
        rec.encoder.clear_buffer(b, 0, None);
    }
    let [x0, y0, x1, y1] = area;
    if x0 >= x1 || y0 >= y1 {
        return;
    }
    let kern = &s.kernels.compose;
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
        ],
    );
    rec.dispatch("compose", kern, &bind, [(x1 - x0).div_ceil(16), (y1 - y0).div_ceil(16), 1]);
}
