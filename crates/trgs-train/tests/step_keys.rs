//! A training step sizes its frame's key list from earlier steps, so its render does not wait for
//! the binning's totals. A view with more keys than that list holds is rendered again, exactly,
//! before the step learns from it: the step must be the one a trainer with an exact list takes.
use trgs_core::fixtures::{SceneSpec, random_scene};
use trgs_core::scene::{Camera, Gaussians};
use trgs_render::{GpuContext, Layer};
use trgs_train::data::View;
use trgs_train::densify::Densification;
use trgs_train::settings::TrainSettings;
use trgs_train::trainer::Trainer;

/// A view of `camera` whose photo is the trainer's own render, darkened.
fn view_of(trainer: &Trainer, camera: &Camera) -> View {
    let ctx = trainer.context();
    let frame = trainer.render(camera).expect("render");
    let mut image = frame.read_layer(ctx, Layer::Color).expect("readback");
    image.data.iter_mut().for_each(|v| *v *= 0.9);
    View::new(camera.clone(), image.quantised())
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
