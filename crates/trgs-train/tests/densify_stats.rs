//! Stage `densify_stats` (the GPU's densification statistics) against its twin
//! `DensifyStats::add`, on a real frame and backward: a scene with two planes, so that the
//! camera's pass and two mirrored passes add to one step, over two steps; then the round trip
//! through a checkpoint's statistics and the reset after an edit.
use trgs_core::fixtures::{SceneSpec, random_scene};
use trgs_core::reference::FrameGrads;
use trgs_core::rng::Rng;
use trgs_core::scene::Gaussians;
use trgs_render::toolkit::gpu::Recorder;
use trgs_render::toolkit::{FrameStages as _, GradientStages as _};
use trgs_render::{
    BackwardOptions, DeviceOptions, Frame, GpuContext, GpuScene, Gradients, LayerGrads,
    RenderOptions, Renderer,
};
use trgs_train::densify::DensifyStats;
use trgs_train::stages::GpuDensifyStats;

fn ctx() -> GpuContext {
    GpuContext::with_options(&DeviceOptions { poison_fresh_buffers: true, ..Default::default() })
        .expect("adapter")
}

/// A frame of a two-plane scene and its backward from random upstream gradients.
fn frame_and_grads(ctx: &GpuContext) -> (Frame, Gradients) {
    let spec = SceneSpec {
        seed: 71,
        gaussians: 800,
        planes: 2,
        width: 96,
        height: 72,
        view_angle_deg: 30.0,
        sh_degree: 1,
        glass_fraction: 0.1,
    };
    let scene = random_scene(&spec);
    let g32: Gaussians<f32> = scene.gaussians.cast();
    let gpu_scene = GpuScene::upload(ctx, &g32, &scene.planes).expect("valid scene");
    let renderer = Renderer::new(ctx);
    let options = RenderOptions { depth_variance: true, ..Default::default() };
    let mut frame = renderer.render(&gpu_scene, &scene.camera, &options).expect("render");
    assert_eq!(frame.views().len(), 3, "the camera's pass and two mirrored passes");
    let (w, h) = (spec.width, spec.height);
    let mut rng = Rng::new(5);
    let grads = FrameGrads::filled(w, h, 2, |im| {
        for v in &mut im.data {
            *v = rng.range(-1.0, 1.0);
        }
    });
    let layer_grads = LayerGrads::upload(ctx, &frame, &grads).expect("finite gradients");
    let out = renderer
        .backward(&gpu_scene, &mut frame, &layer_grads, &BackwardOptions::default())
        .expect("backward");
    (frame, out)
}

#[test]
fn gpu_densify_stats_match_twin() {
    let ctx = ctx();
    let (frame, grads) = frame_and_grads(&ctx);
    let n = frame.gaussian_count() as usize;
    let passes: Vec<_> = (0..frame.views().len())
        .map(|vi| {
            (
                frame.read_projected(&ctx, vi).expect("readback").expect("view"),
                grads.read_projected_grads(&ctx, vi).expect("readback").expect("view"),
            )
        })
        .collect();
    for views in [1, 3] {
        let gpu = GpuDensifyStats::new(&ctx, n);
        let mut twin = DensifyStats::new(n);
        for _ in 0..2 {
            let mut rec = Recorder::new(&ctx, "test.densify_stats", false);
            gpu.record_add(
                &ctx,
                &mut rec,
                &frame,
                &grads,
                views,
                &trgs_train::stages::step_guard::open(&ctx),
            );
            rec.submit_and_wait(&ctx).expect("GPU work");
            twin.add(&passes[..views], frame.width(), frame.height());
        }
        let got = gpu.read(&ctx).expect("readback");
        assert_eq!(got.count, twin.count, "{views} passes: observations");
        assert!(twin.count.contains(&2), "{views} passes: some Gaussians seen");
        assert_eq!(got.max_radius, twin.max_radius, "{views} passes: radii");
        let scale = twin.grad_sum.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(scale > 0.0, "{views} passes: gradients");
        for (i, (a, b)) in got.grad_sum.iter().zip(&twin.grad_sum).enumerate() {
            assert!((a - b).abs() <= 1e-6 * scale + 1e-6 * b.abs(), "{views} passes, {i}: {a} {b}");
        }
        if views == 3 {
            // The mirrored passes add gradients to Gaussians the camera's pass saw too.
            let camera_only = {
                let mut s = DensifyStats::new(n);
                s.add(&passes[..1], frame.width(), frame.height());
                s.add(&passes[..1], frame.width(), frame.height());
                s
            };
            assert!(twin.grad_sum.iter().zip(&camera_only.grad_sum).any(|(a, b)| a > b));
        }
    }
}

#[test]
fn densify_stats_survive_a_checkpoint_and_reset() {
    let ctx = ctx();
    let stats = DensifyStats {
        grad_sum: vec![0.25, 0.0, 3.5e-4],
        count: vec![3, 0, 17],
        max_radius: vec![2.5, 0.0, 40.0],
    };
    let mut gpu = GpuDensifyStats::from_stats(&ctx, &stats);
    assert_eq!(
        gpu.read(&ctx).expect("readback"),
        DensifyStats {
            grad_sum: stats.grad_sum.iter().map(|&v| f64::from(v as f32)).collect(),
            ..stats.clone()
        }
    );
    gpu.reset(&ctx, 5);
    assert_eq!(gpu.read(&ctx).expect("readback"), DensifyStats::new(5));
}
