//! `render_fps`, the render speed `train` and `eval` report, times renders as a viewer pays
//! them (each waited for), not the readback of their images.
use trgs_render::toolkit::gpu::wait_for_gpu;
use trgs_render::{Frame, GpuContext, KeySizing, RenderOptions};
use trgs_synthetic::{SyntheticConfig, generate, write_dataset};
use trgs_train::TrainSettings;
use trgs_train::Trainer;
use trgs_train::eval::{Renderable, render_fps};
use trgs_train::{InitialShape, SeedPoint, gaussians_from_points};
use trgs_train::{LoadOptions, Resolution, TrainingData};

#[test]
fn render_fps_waits_for_each_render_and_reads_no_image_back() {
    let dir = trgs_core::scratch::ScratchDir::new("render-fps");
    let scene = generate(&SyntheticConfig::small());
    write_dataset(&scene, &dir).expect("write the dataset");
    let data = TrainingData::load(
        &trgs_core::io::SceneFolder::open(&dir).expect("open the dataset"),
        &LoadOptions::at(Resolution::Original),
    )
    .expect("load the dataset");
    let seeds: Vec<SeedPoint> =
        data.points.iter().map(|&(position, color)| SeedPoint { position, color }).collect();
    let gaussians = gaussians_from_points(&seeds, 1, InitialShape::CLASSIC);
    let ctx = GpuContext::new().expect("adapter");
    let settings = TrainSettings::scaled(100);
    let trainer =
        Trainer::new(&ctx, &gaussians, &scene.planes, settings, data.extent).expect("trainer");
    let model = Renderable {
        ctx: &ctx,
        renderer: trainer.renderer(),
        scene: trainer.scene(),
        options: trainer.render_options(),
    };
    let views = data.eval_views();
    let (w, h) = (views[0].camera.width(), views[0].camera.height());
    // What the warm-up render costs: the first render into a new frame, sized exactly, then
    // waited for.
    let sized = RenderOptions { key_sizing: KeySizing::FromEarlierFrames, ..model.options.clone() };
    let mut frame = Frame::default();
    let waits = ctx.waits();
    model.renderer.render_into(model.scene, &views[0].camera, &sized, &mut frame).expect("render");
    wait_for_gpu(&ctx, "the warm-up").expect("wait");
    frame.settle_keys(&ctx).expect("totals");
    let warm_up = ctx.waits() - waits;
    // The case: every view's list, sized from the views before it, holds its keys.
    let keys: Vec<u64> = views
        .iter()
        .map(|v| model.renderer.render(model.scene, &v.camera, &model.options).expect("render"))
        .map(|f| f.key_count())
        .collect();
    let mut most = keys[0];
    for &k in &keys {
        assert!(k <= most + most / 4, "keys {keys:?}: a view outgrows the list before it");
        most = most.max(k);
    }

    let (waits, read) = (ctx.waits(), ctx.bytes_read());
    let fps = render_fps(&model, &data).expect("render_fps");
    assert!(fps.is_finite() && fps > 0.0, "{fps}");
    // The warm-up, then each view waited for once: sized exactly, each would wait twice.
    let n = views.len() as u64;
    assert_eq!(ctx.waits() - waits, warm_up + n, "waits for {n} views");
    // Only the key totals come back: well under one image of the views.
    let read = ctx.bytes_read() - read;
    assert!(read < u64::from(w * h) * 4, "{read} bytes read back for {n} renders of {w}x{h}");
}
