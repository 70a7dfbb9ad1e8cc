//! A training step is recorded without waiting for the GPU, and its results are read a step
//! later: recording makes no wait at all ([`GpuContext::waits`]), a pipelined loop trains as
//! steps taken one at a time do, and a frame that outgrows its key list (sized from earlier
//! steps' frames, found only a step later) changes nothing, on the GPU, before the trainer knows;
//! a step taken alone then takes it again, exactly, as a trainer with an exact list would. A
//! profiled step times every phase's passes.
use trgs_core::fixtures::{SceneSpec, random_scene};
use trgs_core::scene::{Camera, Gaussians, ReflectionPlane};
use trgs_render::{DeviceOptions, GpuContext, Layer};
use trgs_train::TrainSettings;
use trgs_train::Trainer;
use trgs_train::View;
use trgs_train::densify::{ClassicSettings, Densification, DensifyEvent, McmcSettings};

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
    trainer_of(ctx, planes, 3000)
}

/// A trainer of a random scene of `gaussians` Gaussians and `planes` planes, and its camera.
fn trainer_of(
    ctx: &GpuContext,
    planes: usize,
    gaussians: usize,
) -> (Trainer, Camera, Gaussians<f32>, Vec<ReflectionPlane>) {
    let scene = random_scene(&SceneSpec { planes, gaussians, ..SceneSpec::default() });
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

/// Densify after every third step: every Gaussian drawn clones (all are under the clone size),
/// nothing is pruned, so that the frames' keys grow past the key list's headroom.
fn classic_every_third_step() -> Densification {
    let mut s = ClassicSettings::scaled(100);
    (s.from, s.every, s.until) = (0, 3, 1000);
    s.grad_threshold = 1e-9;
    s.percent_dense = 1e3;
    s.min_opacity = 0.0;
    Densification::Classic(s)
}

/// Relocate after every third step, and grow by a half.
fn mcmc_every_third_step() -> Densification {
    let mut s = McmcSettings::scaled(100, 100_000);
    (s.from, s.every, s.until) = (0, 3, 1000);
    s.growth = 1.5;
    s.min_opacity = 0.05;
    Densification::Mcmc(s)
}

/// How many Gaussians `event` added.
fn added_by(event: &DensifyEvent) -> usize {
    match event {
        DensifyEvent::Densified(r) => r.cloned + r.split - r.pruned,
        DensifyEvent::Relocated(r) => r.added,
        DensifyEvent::OpacityReset => 0,
    }
}

/// A pipelined loop under `densification` (which changes the set after step 3 and step 6):
/// the maintenance that decides waits for nothing, the next one applies what the steps taken
/// whole applied at once, and the steps after train the new set without waiting or skipping.
fn lands_a_step_later(densification: &Densification) {
    let ctx = ctx();
    // Few Gaussians, so that most are drawn and densifying them adds many keys.
    let (mut pipelined, camera, gaussians, planes) = trainer_of(&ctx, 1, 600);
    let view = view_of(&pipelined, &camera);
    let settings = pipelined.settings.clone();
    let mut whole = Trainer::new(&ctx, &gaussians, &planes, settings, 1.0).expect("trainer");
    pipelined.set_densification(densification).expect("densification");
    whole.set_densification(densification).expect("densification");
    let n = pipelined.scene().len() as usize;
    // Steps taken whole apply step 3's change at once.
    let events: Vec<_> = (0..3).map(|_| whole.train_step(&view).expect("step").densified).collect();
    let [want] = events[2][..] else { panic!("step 3 did not change the set: {events:?}") };
    assert!(added_by(&want) > 0, "{want:?}");

    let first = pipelined.train_step(&view).expect("step 1");
    let second = pipelined.record_step(&view).expect("record");
    assert!(pipelined.maintain().expect("maintain").0.is_empty());
    let third = pipelined.record_step(&view).expect("record");
    let second = pipelined.finish_step(second).expect("finish");
    // Step 3's maintenance decides on the GPU and waits for nothing: the set is unchanged
    // while its counters come back.
    let before = ctx.waits();
    let (events, _) = pipelined.maintain().expect("maintain");
    assert_eq!(ctx.waits(), before, "deciding waited");
    assert!(events.is_empty() && !pipelined.is_settled());
    assert_eq!(pipelined.scene().len() as usize, n);
    // Step 4 trains the set as it was, recorded without a wait.
    let fourth = pipelined.record_step(&view).expect("record");
    let third = pipelined.finish_step(third).expect("finish");
    assert!(!third.skipped && third.record_waits == 0);
    // Its maintenance applies the change: the counters' wait, if they had not arrived, is the
    // only one (step 4 stays queued behind them).
    let before = ctx.waits();
    let (events, _) = pipelined.maintain().expect("maintain");
    assert!(ctx.waits() - before <= 1, "applying the change waited more than once");
    // The same decision as the steps taken whole made (step 4's update comes after it).
    assert_eq!(events, [want]);
    assert_eq!(pipelined.scene().len() as usize, n + added_by(&want));
    assert_eq!(pipelined.scene().len(), whole.scene().len());
    assert!(pipelined.is_settled());
    // The next steps train the new set without waiting: the key list expects the keys' growth
    // instead of being sized exactly, and holds the new frame's keys.
    let fifth = pipelined.record_step(&view).expect("record");
    let fourth = pipelined.finish_step(fourth).expect("finish");
    let sixth = pipelined.record_step(&view).expect("record");
    let fifth = pipelined.finish_step(fifth).expect("finish");
    assert!(pipelined.maintain().expect("maintain").0.is_empty());
    let sixth = pipelined.finish_step(sixth).expect("finish");
    for s in [&fourth, &fifth, &sixth] {
        assert!(!s.skipped && s.loss.is_finite(), "step {} skipped", s.step);
        assert_eq!(s.record_waits, 0, "step {} waited while recorded", s.step);
    }
    // The case needs the headroom: the new set's frames have more keys than a list sized from
    // the old set's frames alone (a quarter over the most they had) holds.
    let most_before = [&first, &second, &third, &fourth].map(|s| s.keys).into_iter().max();
    let most_after = [&fifth, &sixth].map(|s| s.keys).into_iter().max();
    let (before, after) = (most_before.unwrap_or(0), most_after.unwrap_or(0));
    assert!(after > before + before / 4, "keys {before} -> {after}: within the plain headroom");
    // Step 6's maintenance decided again; settling applies it at once.
    let (events, _) = pipelined.settle().expect("settle");
    assert_eq!(events.len(), 1, "{events:?}");
    assert!(pipelined.is_settled());
    pipelined.checkpoint(serde_json::Value::Null).expect("a settled trainer checkpoints");
}

#[test]
fn a_densification_in_a_pipelined_loop_waits_for_nothing_and_lands_a_step_later() {
    lands_a_step_later(&classic_every_third_step());
}

#[test]
fn a_relocation_in_a_pipelined_loop_waits_for_nothing_and_lands_a_step_later() {
    lands_a_step_later(&mcmc_every_third_step());
}

#[test]
fn a_profiled_step_times_the_stages_of_every_phase() {
    // What `bench` divides by the wall clock of a pipelined step (the GPU's busy share): every
    // phase's passes must be in it, the Adam phase's too.
    let ctx = ctx();
    let (mut trainer, camera, _, _) = trainer(&ctx, 1);
    trainer.set_densification(&classic_every_third_step()).expect("densification");
    let view = view_of(&trainer, &camera);
    trainer.profile = true;
    let stats = trainer.train_step(&view).expect("step");
    if !ctx.capabilities.timestamps {
        assert!(stats.gpu_stages.is_empty(), "timed without timestamps");
        return;
    }
    let names: Vec<&str> = stats.gpu_stages.iter().map(|s| s.0).collect();
    for phase_stage in ["project", "rasterize_reflection", "photometric_loss", "step_guard"]
        .into_iter()
        .chain(["rasterize_bwd", "project_bwd", "densify_stats", "adam"])
    {
        assert!(names.contains(&phase_stage), "{phase_stage} is not timed: {names:?}");
    }
    assert!(stats.gpu_stages.iter().all(|s| s.1.is_finite() && s.1 >= 0.0));
    assert!(stats.gpu_stages.iter().map(|s| s.1).sum::<f64>() > 0.0);
}

#[test]
fn a_change_an_edit_applies_on_its_way_is_reported_once_by_the_next_settle() {
    // An edit from outside the maintenance (a new strategy, an edit of the set) applies the
    // change the maintenance left pending first; the next report must still carry it.
    type Edit = fn(&mut Trainer);
    let edits: [(&str, Edit); 2] = [
        ("set_densification", |t| t.set_densification(&Densification::None).expect("set")),
        ("edit_gaussians", |t| t.edit_gaussians(|_, _, _| Ok(())).expect("edit")),
    ];
    let ctx = ctx();
    for (name, edit) in edits {
        let (mut trainer, camera, _, _) = trainer_of(&ctx, 1, 600);
        let view = view_of(&trainer, &camera);
        trainer.set_densification(&classic_every_third_step()).expect("densification");
        for _ in 0..2 {
            trainer.train_step(&view).expect("step");
        }
        let third = trainer.record_step(&view).expect("record");
        trainer.finish_step(third).expect("finish");
        let n = trainer.scene().len() as usize;
        assert!(trainer.maintain().expect("maintain").0.is_empty(), "{name}: applied at once");
        assert!(!trainer.is_settled());
        edit(&mut trainer);
        assert!(trainer.is_settled(), "{name}: the edit left the change pending");
        let (events, _) = trainer.settle().expect("settle");
        let [event] = events[..] else { panic!("{name}: reported {events:?}") };
        assert!(added_by(&event) > 0, "{name}: {event:?}");
        assert_eq!(trainer.scene().len() as usize, n + added_by(&event), "{name}");
        assert!(trainer.settle().expect("settle").0.is_empty(), "{name}: reported twice");
    }
}
