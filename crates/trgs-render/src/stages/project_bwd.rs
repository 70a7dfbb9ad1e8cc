//! Stage `project_bwd` (shaders/backward/project_bwd.wgsl; twin
//! `trgs_core::reference::project_bwd`): from one view's screen-space gradients to the Gaussians'
//! parameters and to the view itself.
use super::Stage;
use super::project::{Candidates, WORK_STRIDE};
use crate::gpu::{self, Recorder, range};
use crate::layout::{BWD_ADD, ProjectParams};
use crate::scene::{GpuScene, SceneGradBuffers};
use crate::toolkit::paged::Paged;
use trgs_core::scene::Attribute;

/// Backpropagate one view: `base` is the view's forward parameter block, `mode` its BWD_* bits
/// (BWD_ADD picks the kernel variant that adds to the gradients, the others go to the kernel).
#[allow(clippy::too_many_arguments)]
pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    scene: &GpuScene,
    base: &ProjectParams,
    mode: u32,
    projected: &Paged,
    candidates: &Candidates,
    projected_grads: &Paged,
    out: &SceneGradBuffers,
    view_grads: wgpu::BindingResource<'_>,
) {
    let k = if mode & BWD_ADD != 0 { &s.kernels.project_bwd_add } else { &s.kernels.project_bwd };
    let coeffs = u64::from(scene.sh_coeffs());
    for (chunk, (first, count)) in scene.chunks().into_iter().enumerate() {
        let [list, work] = candidates.chunk(chunk, first, count);
        let p = ProjectParams { count, sh_coeffs: scene.sh_coeffs(), bwd_mode: mode, ..*base };
        let block = gpu::params(s.ctx, "trgs.project_bwd.params", &p);
        let (f, c) = (u64::from(first), u64::from(count));
        let bind = k.bind(
            s.ctx,
            &[
                block.as_entire_binding(),
                range(scene.parameter(Attribute::Means), f * 12, c * 12),
                range(scene.parameter(Attribute::Rotations), f * 16, c * 16),
                range(scene.parameter(Attribute::LogScales), f * 12, c * 12),
                range(scene.parameter(Attribute::Sh), f * coeffs * 12, c * coeffs * 12),
                projected.range(first, count),
                projected_grads.range(first, count),
                range(out.parameter(Attribute::Means), f * 12, c * 12),
                range(out.parameter(Attribute::Rotations), f * 16, c * 16),
                range(out.parameter(Attribute::LogScales), f * 12, c * 12),
                range(out.parameter(Attribute::OpacityLogits), f * 4, c * 4),
                range(out.parameter(Attribute::Sh), f * coeffs * 12, c * coeffs * 12),
                range(out.parameter(Attribute::MaskLogits), f * 4, c * 4),
                range(out.parameter(Attribute::LogReflections), f * 4, c * 4),
                view_grads.clone(),
                list,
                work,
            ],
        );
        let at = chunk as u64 * WORK_STRIDE;
        rec.dispatch_indirect("project_bwd", k, &bind, &candidates.work, at);
    }
}
