//! Stage `project` (shaders/render/project_candidates.wgsl then shaders/render/project.wgsl;
//! twin `trgs_core::reference::project`): the cheap culls on every Gaussian, every view's in one
//! dispatch (up to CULL_VIEWS views, so that each Gaussian is read and its view-independent
//! terms computed once), then per view the projection of its survivors only, dispatched
//! indirectly over their list (see shaders/shared/project_cull.wgsl for why).
use super::Stage;
use crate::gpu::{self, BufferPool, Recorder, grid_1d, range};
use crate::layout::{CULL_VIEWS, ProjectParams};
use crate::scene::GpuScene;
use crate::toolkit::paged::Paged;
use trgs_core::pipeline::{GUARD_BAND, TileRect};
use trgs_core::scene::Attribute;
use trgs_core::scene::{Intrinsics, ReflectionPlane, ViewTransform};

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

/// Per view, the list of the cheap culls' survivors (chunk by chunk, at the chunk's first
/// Gaussian) and, per chunk, its indirect dispatch and length (`WORK_STRIDE` bytes apart, a
/// binding offset's alignment): `project` and `project_bwd` run over it.
#[derive(Clone, Debug)]
pub struct Candidates {
    pub list: wgpu::Buffer,
    pub work: wgpu::Buffer,
}

// shaders/render/project_candidates.wgsl declares the bindings of exactly this many views.
const _: () = assert!(CULL_VIEWS == 3, "project_candidates.wgsl binds three views");

/// Bytes between two chunks' (workgroups, 1, 1, length) records.
pub const WORK_STRIDE: u64 = 256;

impl Candidates {
    pub fn new(s: Stage<'_>, pool: &mut BufferPool, scene: &GpuScene, view: usize) -> Self {
        let list = pool.get(
            s.ctx,
            &format!("trgs.project.candidates.v{view}"),
            u64::from(scene.len()) * 4,
        );
        // Cleared chunk by chunk before the cull that fills it (see `record_candidates`).
        let work = pool.get(
            s.ctx,
            &format!("trgs.project.work.v{view}"),
            scene.chunks().len().max(1) as u64 * WORK_STRIDE,
        );
        Self { list, work }
    }

    /// The bindings of chunk `c` (first Gaussian `first`, `count` of them): its list and work.
    pub fn chunk(&self, c: usize, first: u32, count: u32) -> [wgpu::BindingResource<'_>; 2] {
        [
            range(&self.list, u64::from(first) * 4, u64::from(count) * 4),
            range(&self.work, c as u64 * WORK_STRIDE, 16),
        ]
    }
}

/// The cheap culls of every view (`params[k]`, `candidates[k]`, `projected[k]`), up to
/// CULL_VIEWS views per dispatch: each Gaussian is read once per group of views. Lists each
/// view's survivors for [`record`].
pub fn record_candidates(
    s: Stage<'_>,
    rec: &mut Recorder,
    scene: &GpuScene,
    params: &[ProjectParams],
    candidates: &[Candidates],
    projected: &[Paged],
) {
    debug_assert!(params.len() == candidates.len() && params.len() == projected.len());
    let cull = &s.kernels.project_candidates;
    let group = CULL_VIEWS as usize;
    let all: Vec<usize> = (0..params.len()).collect();
    for (chunk, (first, count)) in scene.chunks().into_iter().enumerate() {
        let (f, c) = (u64::from(first), u64::from(count));
        let at = chunk as u64 * WORK_STRIDE;
        for views in all.chunks(group) {
            let blocks: Vec<ProjectParams> = views
                .iter()
                .map(|&v| ProjectParams { count, sh_coeffs: scene.sh_coeffs(), ..params[v] })
                .collect();
            let block = gpu::storage_init(s.ctx, "trgs.project.cull_params", &blocks);
            let mut entries = vec![
                block.as_entire_binding(),
                range(scene.parameter(Attribute::Means), f * 12, c * 12),
                range(scene.parameter(Attribute::LogScales), f * 12, c * 12),
                range(scene.parameter(Attribute::OpacityLogits), f * 4, c * 4),
                range(&scene.populations, f * 4, c * 4),
            ];
            // A group of fewer views binds its first view's buffers in the unused slots (the
            // kernel touches only the views `views` holds).
            for k in 0..group {
                let v = views.get(k).copied().unwrap_or(views[0]);
                let [list, work] = candidates[v].chunk(chunk, first, count);
                entries.push(projected[v].range(first, count));
                entries.push(list);
                entries.push(work);
            }
            for &v in views {
                rec.encoder.clear_buffer(&candidates[v].work, at, Some(16));
            }
            let bind = cull.bind(s.ctx, &entries);
            rec.dispatch("project", cull, &bind, grid_1d(count.div_ceil(256)));
        }
    }
}

/// Project the Gaussians of `scene` that [`record_candidates`] listed for this view into
/// `projected` (one record per Gaussian).
pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    scene: &GpuScene,
    base: &ProjectParams,
    candidates: &Candidates,
    projected: &Paged,
) {
    let k = &s.kernels.project;
    let coeffs = u64::from(scene.sh_coeffs());
    for (chunk, (first, count)) in scene.chunks().into_iter().enumerate() {
        let [list, work] = candidates.chunk(chunk, first, count);
        let p = ProjectParams { count, sh_coeffs: scene.sh_coeffs(), ..*base };
        let block = gpu::params(s.ctx, "trgs.project.params", &p);
        let (f, c) = (u64::from(first), u64::from(count));
        let out = projected.range(first, count);
        let bind = k.bind(
            s.ctx,
            &[
                block.as_entire_binding(),
                range(scene.parameter(Attribute::Means), f * 12, c * 12),
                range(scene.parameter(Attribute::Rotations), f * 16, c * 16),
                range(scene.parameter(Attribute::LogScales), f * 12, c * 12),
                range(scene.parameter(Attribute::OpacityLogits), f * 4, c * 4),
                range(scene.parameter(Attribute::Sh), f * coeffs * 12, c * coeffs * 12),
                range(scene.parameter(Attribute::MaskLogits), f * 4, c * 4),
                range(scene.parameter(Attribute::LogReflections), f * 4, c * 4),
                range(&scene.populations, f * 4, c * 4),
                out,
                list,
                work,
            ],
        );
        let at = chunk as u64 * WORK_STRIDE;
        rec.dispatch_indirect("project", k, &bind, &candidates.work, at);
    }
}
