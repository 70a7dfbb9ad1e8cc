//! The backward measurement of `bench`: forward and backward of one training-like step.
use super::common::{median, room_100k, upload, warm_up};
use anyhow::Result;
use std::time::Instant;
use trgs_core::fixtures::RoomDensity;
use trgs_core::reference::FrameGrads;
use trgs_render::{BackwardOptions, Frame, GpuContext, LayerGrads, RenderOptions, Renderer};

/// Forward and backward of one training-like step on one scene (256x192, 100k Gaussians).
pub struct BackwardRow {
    pub density: RoomDensity,
    pub planes: usize,
    pub steps: usize,
    pub forward_ms: f64,
    pub backward_ms: f64,
    /// Median over steps of backward / forward.
    pub ratio: f64,
    /// Median GPU ms per backward stage.
    pub stages: Vec<(&'static str, f64)>,
}

/// Upstream gradients with deterministic values in [-1, 1] on every layer (a loss that depends
/// on all of them, so that no adjoint stage can skip work).
fn pseudo_grads(w: u32, h: u32, planes: usize) -> FrameGrads {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    FrameGrads::filled(w, h, planes, |im| {
        for v in &mut im.data {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            *v = ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0;
        }
    })
}

pub fn bench_backward(
    ctx: &GpuContext,
    renderer: &Renderer,
    density: RoomDensity,
    planes: usize,
    steps: usize,
) -> Result<BackwardRow> {
    let spec = room_100k(planes, density);
    let (scene, camera) = upload(ctx, &spec)?;
    // As training renders: with the depth-variance layer.
    let options = RenderOptions { depth_variance: true, ..RenderOptions::default() };
    let grads = pseudo_grads(spec.width, spec.height, planes);
    let mut frame = Frame::default();
    let plain = BackwardOptions::default();
    // JIT, buffer pools, clocks.
    warm_up(|| -> Result<()> {
        renderer.render_into(&scene, &camera, &options, &mut frame)?;
        let layer_grads = LayerGrads::upload(ctx, &frame, &grads)?;
        renderer.backward(&scene, &mut frame, &layer_grads, &plain)?;
        Ok(())
    })?;
    let (mut fwd, mut bwd, mut ratios) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..steps {
        let t = Instant::now();
        renderer.render_into(&scene, &camera, &options, &mut frame)?;
        let f = t.elapsed().as_secs_f64() * 1e3;
        // A fresh copy of the upstream gradients (the backward consumes them), not timed.
        let layer_grads = LayerGrads::upload(ctx, &frame, &grads)?;
        let t = Instant::now();
        let out = renderer.backward(&scene, &mut frame, &layer_grads, &plain)?;
        // The backward does not wait for its GPU work: the timed span ends when it is done.
        trgs_render::toolkit::gpu::wait_for_gpu(ctx, "the backward")?;
        out.planes.read(ctx)?;
        let b = t.elapsed().as_secs_f64() * 1e3;
        fwd.push(f);
        bwd.push(b);
        ratios.push(b / f);
    }
    let profiled = BackwardOptions { profile: true, ..plain };
    let mut samples: Vec<(&'static str, Vec<f64>)> = Vec::new();
    for _ in 0..steps {
        renderer.render_into(&scene, &camera, &options, &mut frame)?;
        let layer_grads = LayerGrads::upload(ctx, &frame, &grads)?;
        let out = renderer.backward(&scene, &mut frame, &layer_grads, &profiled)?;
        for &(name, ms) in out.stage_times().unwrap_or_default() {
            match samples.iter_mut().find(|s| s.0 == name) {
                Some(s) => s.1.push(ms),
                None => samples.push((name, vec![ms])),
            }
        }
    }
    Ok(BackwardRow {
        density,
        planes,
        steps,
        forward_ms: median(fwd),
        backward_ms: median(bwd),
        ratio: median(ratios),
        stages: samples.into_iter().map(|(n, v)| (n, median(v))).collect(),
    })
}
