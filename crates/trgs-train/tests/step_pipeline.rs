//! A training step is recorded without waiting for the GPU, and its results are read a step
//! later: recording makes no wait at all ([`GpuContext::waits`]), a pipelined loop trains as
//! steps taken one at a time do, and a frame that outgrows its key list (sized from earlier
//! steps' frames, found only a step later) changes nothing, on the GPU, before the trainer knows;
//! a step taken alone then takes it again, exactly, as a trainer with an exact list would.
use trgs_core::fixtures::{SceneSpec, random_scene};
use trgs_core::scene::{Camera, Gaussians, ReflectionPlane};
use trgs_render::{DeviceOptions, GpuContext, Layer};
use trgs_train::data::View;
use trgs_train::densify::Densification;
use trgs_train::settings::TrainSettings;
use trgs_train::trainer::Trainer;

/// A context that records while the device is busy, as on a GPU (a CPU adapter waits between a
/// step's phases by default, `Capabilities::records_while_busy`).
fn ctx() -> GpuContext {
    let options = DeviceOptions { records_while_busy: Some(true), ..Default::default() };
    GpuContext::with_options(&options).expect("adapter")
}

/// A view of `camera` whose photo is the trainer's own render, darkened.
fn view_of(trainer: &Trainer, camera: &Camera) -> View {
    let ctx = trainer.context();
    let frame = trainer.render(camera).expect("render");
    let mut image = frame.read_layer(ctx, Layer::Color).expect("readback");
    image.data.iter_mut().for_each(|v| *v *= 0.9);
    View::new(camera.clone(), image.quantised())
}

fn trainer(
    ctx: &GpuContext,
    planes: usize,
) -> (Trainer, Camera, Gaussians<f32>, Vec<ReflectionPlane>) {
    let scene = random_scene(&SceneSpec { planes, gaussians: 3000, ..SceneSpec::default() });
    let gaussians = scene.gaussians.cast::<f32>();
    let settings = TrainSettings::scaled(100);
    let t = Trainer::new(ctx, &gaussians, &scene.planes, settings, 1.0).expect("trainer");
    (t, scene.camera, gaussians, scene.planes)
}

#[test]
fn recording_a_step_waits_for_nothing() {
    let ctx = ctx();
    for planes in [0, 1] {
        let (mut trainer, camera, _, _) = trainer(&ctx, planes);
        let view = view_of(&trainer, &camera);
        // The first step sizes the frame's key list exactly (it has no earlier frame).
        trainer.train_step(&view).expect("step");
        let before = ctx.waits();
        let first = trainer.record_step(&view).expect("record");
        let second = trainer.record_step(&view).expect("record");
        assert_eq!(ctx.waits(), before, "{planes} planes: recording two steps waited");
        // Finishing the first waits for its own work only; the second is still queued.
        let a = trainer.finish_step(first).expect("finish");
        let b = trainer.finish_step(second).expect("finish");
        assert_eq!((a.step, b.step), (2, 3));
        assert_eq!((a.record_waits, b.record_waits), (0, 0));
        assert!(!a.skipped && !b.skipped && a.loss.is_finite() && b.loss.is_finite());
    }
}

#[test]
fn a_pipelined_loop_trains_as_single_steps_do() {
    let ctx = ctx();
    let (mut single, camera, gaussians, planes) = trainer(&ctx, 0);
    let view = view_of(&single, &camera);
    let settings = single.settings.clone();
    let mut pipelined = Trainer::new(&ctx, &gaussians, &planes, settings, 1.0).expect("trainer");
    let steps = 6;
    let want: Vec<f64> = (0..steps).map(|_| single.train_step(&view).expect("step").loss).collect();
    let mut got = Vec::new();
    let mut in_flight = pipelined.record_step(&view).expect("record");
    for _ in 1..steps {
        let next = pipelined.record_step(&view).expect("record");
        pipelined.maintain().expect("maintain");
        got.push(pipelined.finish_step(std::mem::replace(&mut in_flight, next)).expect("finish"));
    }
    got.push(pipelined.finish_step(in_flight).expect("finish"));
    for (k, (s, w)) in got.iter().zip(&want).enumerate() {
        assert!(!s.skipped, "step {k} skipped");
        // The backward adds with float atomics, whose order varies: the losses agree to rounding.
        assert!((s.loss - w).abs() <= 1e-5 * w.abs(), "step {k}: loss {} against {w}", s.loss);
    }
    let (a, b) = (single.gaussians().expect("read"), pipelined.gaussians().expect("read"));
    let worst = largest_difference(&a, &b);
    assert!(worst < 1e-5, "the Gaussians differ by up to {worst:e}");
}

#[test]
fn a_frame_that_outgrows_its_list_changes_nothing_before_it_is_known() {
    let ctx = ctx();
    let (mut trainer, camera, _, _) = trainer(&ctx, 1);
    // The same camera at a sixteenth of the pixels: far fewer tile keys, so that the list
    // sized from it cannot hold the big view's.
    let mut small = camera.clone();
    let k = &camera.intrinsics;
    small.intrinsics = k.resized(k.width / 4, k.height / 4);
    small.name = format!("{} at a quarter size", small.name);
    let (small_view, big_view) = (view_of(&trainer, &small), view_of(&trainer, &camera));
    trainer.train_step(&small_view).expect("step");
    let before = trainer.gaussians().expect("read");
    let planes_before = trainer.planes().to_vec();
    let in_flight = trainer.record_step(&big_view).expect("record");
    let stats = trainer.finish_step(in_flight).expect("finish");
    assert!(stats.skipped, "the list sized from the small view held the big one");
    assert_eq!(trainer.gaussians().expect("read"), before, "a skipped step moved Gaussians");
    assert_eq!(trainer.planes(), &planes_before[..], "a skipped step moved the plane");
    // The next frame is sized exactly, and trains.
    let next = trainer.record_step(&big_view).expect("record");
    let stats = trainer.finish_step(next).expect("finish");
    assert!(!stats.skipped && stats.keys > 0);
    assert!(largest_difference(&trainer.gaussians().expect("read"), &before) > 0.0);
}

#[test]
fn a_step_whose_frame_outgrows_its_key_list_learns_from_the_exact_frame() {
    let ctx = GpuContext::new().expect("adapter");
    let scene = random_scene(&SceneSpec { planes: 1, gaussians: 3000, ..SceneSpec::default() });
    let gaussians = scene.gaussians.cast::<f32>();
    let settings = TrainSettings::scaled(100);
    let mut trainer =
        Trainer::new(&ctx, &gaussians, &scene.planes, settings.clone(), 1.0).expect("trainer");
    // The same camera at a sixteenth of the pixels: far fewer tile keys. The list sized from
    // it drops most of the big view's keys, the back ones (the keys are emitted front to
    // back), so that the dropped ones change the image and not only the gradients.
    let mut small = scene.camera.clone();
    let k = &scene.camera.intrinsics;
    small.intrinsics = k.resized(k.width / 4, k.height / 4);
    small.name = format!("{} at a quarter size", small.name);
    let (small_view, big_view) = (view_of(&trainer, &small), view_of(&trainer, &scene.camera));
    let few = trainer.train_step(&small_view).expect("step").keys;

    // A trainer in the same state whose frame has held nothing yet renders exactly.
    let ck = trainer.checkpoint(serde_json::Value::Null).expect("checkpoint");
    let mut exact =
        Trainer::from_checkpoint(&ctx, &ck, settings, 1.0, &Densification::None).expect("resume");
    let want = exact.train_step(&big_view).expect("step");
    assert!(want.keys > few + few / 4, "{few} keys, then {}: the list must overflow", want.keys);

    let got = trainer.train_step(&big_view).expect("step");
    assert_eq!(got.keys, want.keys, "the step's keys");
    assert_eq!(got.loss.to_bits(), want.loss.to_bits(), "the step's loss");
    // The backward adds gradients with float atomics, whose order varies from run to run: the
    // parameters agree to rounding, far below what one Adam step moves them (1e-4 and more).
    let (a, b) = (trainer.gaussians().expect("read"), exact.gaussians().expect("read"));
    let worst = largest_difference(&a, &b);
    assert!(worst < 1e-6, "the Gaussians after the step differ by up to {worst:e}");
    // And the next step's list is sized from the overflowed frame: it holds the big view.
    let next = trainer.train_step(&big_view).expect("step");
    assert!(next.keys > 0);
}

/// The largest difference between any two parameters of `a` and `b`.
fn largest_difference(a: &Gaussians<f32>, b: &Gaussians<f32>) -> f32 {
    assert_eq!(a.len(), b.len());
    let flat = |g: &Gaussians<f32>| -> Vec<f32> {
        let mut v: Vec<f32> = g.means.iter().flatten().copied().collect();
        v.extend(g.rotations.iter().flatten());
        v.extend(g.log_scales.iter().flatten());
        v.extend(&g.opacity_logits);
        v.extend(g.sh.iter().flatten());
        v.extend(&g.mask_logits);
        v.extend(&g.log_reflections);
        v
    };
    flat(a).iter().zip(flat(b)).map(|(x, y)| (x - y).abs()).fold(0.0, f32::max)
}
