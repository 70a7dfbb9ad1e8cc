//! `render_fps`, the render speed `train` and `eval` report, times renders as a viewer pays
//! them (each waited for), not the readback of their images.
use trgs_core::synthetic::{SyntheticConfig, generate, write_dataset};
use trgs_render::GpuContext;
use trgs_train::data::{self, Resolution};
use trgs_train::eval::{Renderable, render_fps};
use trgs_train::init::{InitialShape, SeedPoint, gaussians_from_points};
use trgs_train::settings::TrainSettings;
use trgs_train::trainer::Trainer;

/// The most waits of the warm-up render into a new frame.
const WARM_UP_WAITS: u64 = 4;

#[test]
fn render_fps_waits_for_each_render_and_reads_no_image_back() {
    let dir = trgs_core::scratch::ScratchDir::new("render-fps");
    let scene = generate(&SyntheticConfig::small());
    write_dataset(&scene, &dir).expect("write the dataset");
    let data = data::load(&dir, Resolution::Original).expect("load the dataset");
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
    let (waits, read) = (ctx.waits(), ctx.bytes_read());
    let fps = render_fps(&model, &data).expect("render_fps");
    assert!(fps.is_finite() && fps > 0.0, "{fps}");
    // The warm-up render, the first into its frame, sizes its key list exactly (a wait halfway
    // and one at its end, and setting up); the timed ones are sized from it and each waited for
    // once, as the lists hold their keys here. Sized exactly, each would wait at least twice.
    let waited = ctx.waits() - waits;
    let n = views.len() as u64;
    assert!((n..=n + WARM_UP_WAITS).contains(&waited), "{waited} waits for {n} views");
    // Only the key totals come back: well under one image of the views.
    let read = ctx.bytes_read() - read;
    assert!(read < u64::from(w * h) * 4, "{read} bytes read back for {n} renders of {w}x{h}");
}
