//! Stage `display` against its twin: every layer of frames with zero, one and two planes (and an
//! odd width, so that rows are padded), from the same layer buffer the GPU read. Fresh buffers are
//! poison-filled, so pixels the stage forgets to write show up.
use trgs_core::fixtures::random_scene;
use trgs_core::reference::display;
use trgs_render::toolkit::gpu;
use trgs_render::{
    DeviceOptions, DisplayError, DisplayTarget, GpuContext, GpuScene, Layer, RenderOptions,
    Renderer, layer_mapping,
};

mod common;
use common::spec;

fn ctx() -> GpuContext {
    let opts = DeviceOptions { poison_fresh_buffers: true, ..Default::default() };
    GpuContext::with_options(&opts).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn every_layer_matches_the_twin() {
    let ctx = ctx();
    let renderer = Renderer::new(&ctx);
    for (seed, planes, width) in [(3, 0, 96), (4, 1, 77), (5, 2, 33)] {
        let mut s = spec(seed, 300, planes, 20.0);
        s.width = width;
        let scene = random_scene(&s);
        let gpu_scene =
            GpuScene::upload(&ctx, &scene.gaussians.cast::<f32>(), &scene.planes).expect("valid");
        let frame =
            renderer.render(&gpu_scene, &scene.camera, &RenderOptions::default()).expect("renders");
        let (w, h) = (frame.width(), frame.height());
        let target = DisplayTarget::new(&ctx, w, h).expect("allocation");
        for layer in Layer::ALL {
            let range = [0.5, 6.0];
            renderer.display(&frame, layer, range, &target).expect("displays");
            let (buffer, mapping) = layer_mapping(&frame, layer, range).expect("rendered");
            let input: Vec<[f32; 4]> =
                gpu::read_buffer(&ctx, buffer, 0, (w * h) as usize).expect("readback");
            let want = display(&input, mapping);
            let got = target.read_rgba(&ctx).expect("readback");
            let mut worst = 0i32;
            for (p, &word) in want.iter().enumerate() {
                for (c, &b) in word.to_le_bytes().iter().enumerate() {
                    worst = worst.max((i32::from(got.data[p * 4 + c]) - i32::from(b)).abs());
                }
            }
            // pack4x8unorm may round a value at exactly k + 0.5 either way (fma or not).
            assert!(worst <= 1, "seed {seed} {layer:?}: worst difference {worst} levels");
        }
    }
}

#[test]
fn a_target_of_another_size_is_refused() {
    let ctx = ctx();
    let renderer = Renderer::new(&ctx);
    let scene = random_scene(&spec(1, 50, 0, 0.0));
    let gpu_scene =
        GpuScene::upload(&ctx, &scene.gaussians.cast::<f32>(), &scene.planes).expect("valid");
    let frame =
        renderer.render(&gpu_scene, &scene.camera, &RenderOptions::default()).expect("renders");
    let target = DisplayTarget::new(&ctx, frame.width() + 1, frame.height()).expect("allocation");
    let err = renderer.display(&frame, Layer::Color, [0.5, 6.0], &target).expect_err("size");
    assert!(matches!(err, DisplayError::SizeMismatch { .. }), "{err}");
}
