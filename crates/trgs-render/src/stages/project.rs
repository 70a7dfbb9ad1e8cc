//! Stage `project` (shaders/project_candidates.wgsl then shaders/project.wgsl; twin
//! `trgs_core::reference::project`): the cheap culls on every Gaussian, then the projection of the
//! survivors only, dispatched indirectly over their list (see shared/project_cull.wgsl for why).
use super::Stage;
use crate::gpu::{self, BufferPool, Recorder, grid_1d, range};
use crate::layout::{ProjectParams, ProjectedGaussian};
use crate::scene::GpuScene;
use trgs_core::reference::{GUARD_BAND, TileRect};
use trgs_core::scene::{Intrinsics, ReflectionPlane, ViewTransform};

const PROJECTED: u64 = std::mem::size_of::<ProjectedGaussian>() as u64;

/// The parameter block of one view: `plane` is Some for a mirrored view (front-side filter).
pub fn params(
    view: &ViewTransform,
    k: &Intrinsics,
    plane: Option<&ReflectionPlane>,
    limit: &TileRect,
    near: f64,
    sh_degree: u32,
) -> ProjectParams {
    let v4 = |v: glam::DVec3, w: f64| [v.x as f32, v.y as f32, v.z as f32, w as f32];
    let rows = view.linear.transpose();
    let (w, h) = (f64::from(k.width), f64::from(k.height));
    let tan_limits = [
        (-GUARD_BAND * w - k.cx) / k.fx,
        ((1.0 + GUARD_BAND) * w - k.cx) / k.fx,
        (-GUARD_BAND * h - k.cy) / k.fy,
        ((1.0 + GUARD_BAND) * h - k.cy) / k.fy,
    ];
    let (pc, pn) =
        plane.map_or((glam::DVec3::ZERO, glam::DVec3::ZERO), |p| (p.centre, p.unit_normal()));
    ProjectParams {
        row0: v4(rows.x_axis, 0.0),
        row1: v4(rows.y_axis, 0.0),
        row2: v4(rows.z_axis, 0.0),
        translation: v4(view.translation, 0.0),
        centre: v4(view.centre, 0.0),
        plane_centre: v4(pc, 0.0),
        plane_normal: v4(pn, 0.0),
        focal: [k.fx as f32, k.fy as f32, k.cx as f32, k.cy as f32],
        tan_limits: tan_limits.map(|v| v as f32),
        count: 0,
        sh_degree,
        sh_coeffs: 0,
        front_only: u32::from(plane.is_some()),
        near: near as f32,
        width: k.width,
        height: k.height,
        limit: [limit.x0, limit.y0, limit.x1, limit.y1],
        ..Default::default()
    }
}

/// The list of the cheap culls' survivors and its indirect dispatch, reused by every view and
/// chunk (their passes run in recording order).
#[derive(Debug)]
pub struct Scratch {
    candidates: wgpu::Buffer,
    work: wgpu::Buffer,
}

impl Scratch {
    pub fn new(s: Stage<'_>, pool: &mut BufferPool, scene: &GpuScene) -> Self {
        let most = scene.chunks().iter().map(|c| c.1).max().unwrap_or(0);
        let candidates = pool.get(s.ctx, "trgs.project.candidates", u64::from(most.max(1)) * 4);
        let work = s.ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("trgs.project.work"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::INDIRECT
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self { candidates, work }
    }
}

/// Project every Gaussian of `scene` into `projected` (one record per Gaussian).
pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    scene: &GpuScene,
    base: &ProjectParams,
    scratch: &Scratch,
    projected: &wgpu::Buffer,
) {
    let (cull, k) = (&s.kernels.project_candidates, &s.kernels.project);
    let coeffs = u64::from(scene.sh_coeffs());
    let list = scratch.candidates.as_entire_binding();
    for (first, count) in scene.chunks() {
        let p = ProjectParams { count, sh_coeffs: scene.sh_coeffs(), ..*base };
        let block = gpu::params(s.ctx, "trgs.project.params", &p);
        let (f, c) = (u64::from(first), u64::from(count));
        let out = range(projected, f * PROJECTED, c * PROJECTED);
        let bind = cull.bind(
            s.ctx,
            &[
                block.as_entire_binding(),
                range(&scene.means, f * 12, c * 12),
                range(&scene.log_scales, f * 12, c * 12),
                range(&scene.opacity_logits, f * 4, c * 4),
                range(&scene.populations, f * 4, c * 4),
                out.clone(),
                list.clone(),
                scratch.work.as_entire_binding(),
            ],
        );
        rec.encoder.clear_buffer(&scratch.work, 0, None);
        rec.dispatch("project", cull, &bind, grid_1d(count.div_ceil(256)));
        let bind = k.bind(
            s.ctx,
            &[
                block.as_entire_binding(),
                range(&scene.means, f * 12, c * 12),
                range(&scene.rotations, f * 16, c * 16),
                range(&scene.log_scales, f * 12, c * 12),
                range(&scene.opacity_logits, f * 4, c * 4),
                range(&scene.sh, f * coeffs * 12, c * coeffs * 12),
                range(&scene.mask_logits, f * 4, c * 4),
                range(&scene.log_reflections, f * 4, c * 4),
                range(&scene.populations, f * 4, c * 4),
                out,
                list.clone(),
                scratch.work.as_entire_binding(),
            ],
        );
        rec.dispatch_indirect("project", k, &bind, &scratch.work, 0);
    }
}
