//! Phase 2 of a render, the images: pass 1 over the camera's view, pass 2 over each mirrored
//! view's footprint, then compose.
use super::job::RenderJob;
use crate::frame::{LayerBuffers, ViewBuffers};
use crate::gpu::Recorder;
use crate::stages::compose::{self, RayBuffers};
use crate::stages::rasterize::{self, Pass1Outputs};
use crate::stages::rasterize_reflection;

/// What the frame keeps of compose (compose_bwd reads it).
#[derive(Debug)]
pub(super) struct Composed {
    /// Per plane: whether its mirrored pass ran.
    pub has_pass: Vec<bool>,
    /// The camera rays and planes compose read.
    pub rays: RayBuffers,
}

/// Records both rasterize passes of `views` (the camera's first, then the mirrored ones, their
/// keys sorted) and compose into `layers`.
pub(super) fn rasterize_and_compose(
    rec: &mut Recorder,
    job: &RenderJob<'_>,
    views: &[ViewBuffers],
    layers: &LayerBuffers,
) -> Composed {
    let planes = job.scene.planes();
    rasterize_camera(rec, job, &views[0], layers);
    let mut has_pass = vec![false; planes.len()];
    for v in &views[1..] {
        has_pass[v.plane.unwrap_or(0)] = true;
    }
    let planes_gpu = compose::planes_gpu(planes, &has_pass);
    let rays = RayBuffers::new(job.s, job.camera, &planes_gpu, job.options.reflection);
    if views.len() == 1 {
        // No plane hit anywhere: H = 0, which compose_bwd reads.
        rec.encoder.clear_buffer(&layers.hit, 0, None);
    } else {
        reflect_and_compose(rec, job, &views[1..], &rays, layers);
    }
    Composed { has_pass, rays }
}

/// Pass 1 over the camera's view: C_t, D_t, M, alpha, [V].
fn rasterize_camera(
    rec: &mut Recorder,
    job: &RenderJob<'_>,
    primary: &ViewBuffers,
    layers: &LayerBuffers,
) {
    #[allow(clippy::expect_used)]
    let (p_values, p_ranges) = (
        &primary.keys.as_ref().expect("sorted before the passes").values,
        primary.ranges.as_ref().expect("set before the passes"),
    );
    rasterize::record(
        job.s,
        rec,
        &job.grid,
        job.options.background,
        job.options.depth_variance,
        &primary.projected,
        p_values,
        p_ranges,
        &Pass1Outputs {
            transmission: &layers.transmission,
            geometry: &layers.geometry,
            states: &layers.states,
        },
    );
}

/// Pass 2 of each view of `mirrored` over its footprint, into its plane's slot (C_raw, A), then
/// compose over the footprints (C, R, C_r).
fn reflect_and_compose(
    rec: &mut Recorder,
    job: &RenderJob<'_>,
    mirrored: &[ViewBuffers],
    rays: &RayBuffers,
    layers: &LayerBuffers,
) {
    let (s, grid) = (job.s, &job.grid);
    rec.encoder.clear_buffer(&layers.reflection_raw, 0, None);
    rec.encoder.clear_buffer(&layers.reflection_states, 0, None);
    for v in mirrored {
        #[allow(clippy::expect_used)]
        let (keys, ranges) = (
            v.keys.as_ref().expect("sorted before the passes"),
            v.ranges.as_ref().expect("set before the passes"),
        );
        let slot = v.plane.unwrap_or(0) as u32;
        rasterize_reflection::record(
            s,
            rec,
            grid,
            slot,
            &v.limit,
            v.tile_base,
            &v.projected,
            &keys.values,
            ranges,
            &layers.reflection_raw,
            &layers.reflection_states,
            rays,
        );
    }
    let footprints: Vec<_> = mirrored.iter().map(|v| v.limit).collect();
    compose::record(
        s,
        rec,
        grid,
        &footprints,
        rays,
        &layers.transmission,
        &layers.geometry,
        &layers.reflection_raw,
        &compose::ComposeOutputs {
            color: &layers.color,
            reflection: &layers.reflection,
            strength: &layers.strength,
            hit: &layers.hit,
        },
    );
}
