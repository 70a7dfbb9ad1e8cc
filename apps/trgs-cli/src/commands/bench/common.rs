//! What the measurements share: the warm-up before timing, the median of the timed runs and the
//! 100k-Gaussian room they measure on.
use anyhow::Result;
use std::time::Instant;
use trgs_core::fixtures::{RoomDensity, RoomSpec, room_scene};
use trgs_render::{GpuContext, GpuScene};

/// How long each configuration runs untimed before it is timed. One frame compiles the
/// pipelines and fills the buffer pools; a real GPU also has to leave the idle clocks it drops to
/// while the CPU builds the next scene (after a one-frame warm-up an H100 timed whole
/// configurations several times slower in every stage). On lavapipe this adds a frame or two.
const WARM_UP_SECONDS: f64 = 0.5;

/// Runs `step` once, then again until `WARM_UP_SECONDS` have passed.
pub(crate) fn warm_up<E>(mut step: impl FnMut() -> Result<(), E>) -> Result<(), E> {
    let start = Instant::now();
    step()?;
    while start.elapsed().as_secs_f64() < WARM_UP_SECONDS {
        step()?;
    }
    Ok(())
}

/// The median of the timed runs.
pub(crate) fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The room of `spec` on the GPU, with its camera.
pub(crate) fn upload(
    ctx: &GpuContext,
    spec: &RoomSpec,
) -> Result<(GpuScene, trgs_core::scene::Camera)> {
    let scene = room_scene(spec);
    let gpu_scene = GpuScene::upload(ctx, &scene.gaussians.cast::<f32>(), &scene.planes)?;
    Ok((gpu_scene, scene.camera))
}

/// The room at 256x192 with 100k Gaussians and SH degree 3: the configuration of the plane-cost,
/// backward and training-step measurements.
pub(crate) fn room_100k(planes: usize, density: RoomDensity) -> RoomSpec {
    RoomSpec { seed: 7, gaussians: 100_000, planes, width: 256, height: 192, sh_degree: 3, density }
}
