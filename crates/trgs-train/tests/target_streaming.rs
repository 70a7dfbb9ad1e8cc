//! Training views streamed under a GPU memory budget: a trainer holding two views at a time
//! (each view uploaded a step ahead, the least recently used dropped) makes the losses of one
//! holding every view (to the order of atomic sums), and a budget that cannot hold one view is
//! refused before the photos load, naming the view and the flag.
use trgs_core::scratch::ScratchDir;
use trgs_render::GpuContext;
use trgs_synthetic::{SyntheticConfig, generate, write_dataset};
use trgs_train::TrainSettings;
use trgs_train::Trainer;
use trgs_train::stages::targets::{self, TargetCounts};
use trgs_train::{InitialShape, SeedPoint, gaussians_from_points};
use trgs_train::{LoadOptions, Resolution, TrainingData};
use trgs_train::{RunConfig, RunOptions, TrainingRun};

#[test]
fn streamed_views_train_as_resident_ones() {
    let dir = ScratchDir::new("target-streaming");
    write_dataset(&generate(&SyntheticConfig::small()), &dir).expect("write the dataset");
    let data = TrainingData::load(
        &trgs_core::io::SceneFolder::open(&dir).expect("open the dataset"),
        &LoadOptions::at(Resolution::Original),
    )
    .expect("load the dataset");
    let seeds: Vec<SeedPoint> =
        data.points.iter().map(|&(position, color)| SeedPoint { position, color }).collect();
    let gaussians = gaussians_from_points(&seeds, 1, InitialShape::CLASSIC);
    let ctx = GpuContext::new().expect("adapter");
    let mut settings = TrainSettings::scaled(40);
    settings.sh_degree = 1;
    let trainer = || Trainer::new(&ctx, &gaussians, &[], settings.clone(), data.extent);
    let (mut resident, mut streamed) = (trainer().expect("trainer"), trainer().expect("trainer"));
    let bytes: Vec<u64> = data.train.iter().map(targets::target_bytes).collect();
    let largest = bytes.iter().copied().max().expect("views");
    resident.set_target_budget(u64::MAX);
    streamed.set_target_budget(2 * largest);
    let order: Vec<usize> = (0..data.train.len()).chain(0..data.train.len()).collect();
    let mut losses = Vec::new();
    for (k, &vi) in order.iter().enumerate() {
        let want = resident.train_step(&data.train[vi]).expect("resident step").loss;
        let before = streamed.targets().counts().uploads;
        let got = streamed.train_step(&data.train[vi]).expect("streamed step").loss;
        losses.push((want, got));
        if k > 0 {
            let uploads = streamed.targets().counts().uploads;
            assert_eq!(uploads, before, "step {k}: its view was not uploaded ahead");
        }
        if let Some(&next) = order.get(k + 1) {
            streamed.prefetch(&data.train[next]).expect("prefetch");
        }
    }
    let views = data.train.len() as u64;
    assert_eq!(
        resident.targets().counts(),
        TargetCounts {
            uploads: views,
            evictions: 0,
            uploads_in_step: views,
            resident_bytes: bytes.iter().sum()
        },
        "every view uploaded once and kept"
    );
    // At most three views fit: the second pass over the views uploads them again.
    let counts = streamed.targets().counts();
    assert!(counts.uploads >= order.len() as u64 * 2 / 3, "{counts:?}");
    assert!(counts.evictions + 3 >= counts.uploads, "{counts:?}");
    assert!(counts.resident_bytes <= 2 * largest, "{counts:?}");
    // The same steps on the same targets. The first step's loss is the same to the bit; after
    // it the two differ by the order of the backward pass's atomic sums only.
    eprintln!("losses, resident and streamed: {losses:?}");
    assert_eq!(losses[0].0, losses[0].1, "the first step saw another target");
    for (k, (want, got)) in losses.iter().enumerate() {
        assert!((want - got).abs() <= 1e-4 * want, "step {k}: loss {got}, resident {want}");
    }
}

/// A run that streams its views uploads each one ahead of its step, the first view of every
/// epoch included (its order is drawn when the previous epoch ends): only the very first step
/// uploads its own view.
#[test]
fn a_run_uploads_every_view_ahead_across_epochs() {
    let dir = ScratchDir::new("target-epochs");
    let scene = dir.join("data");
    // 320x240: about 0.3 MiB a view, so a budget of 1 MiB holds three of the ten training views.
    let synthetic = SyntheticConfig { width: 320, height: 240, ..SyntheticConfig::small() };
    write_dataset(&generate(&synthetic.without_glass()), &scene).expect("dataset");
    let config = RunConfig {
        data: Some(scene),
        out: dir.join("run"),
        iterations: 25,
        eval_every: Some(1000),
        sh_degree: 0,
        target_memory: Some(1),
        ..RunConfig::default()
    };
    let mut run = TrainingRun::start(config, RunOptions::default()).expect("run");
    run.run_to_end(|_| {}).expect("training");
    let train_views = run.trainer().targets().counts();
    assert!(train_views.evictions > 0, "the views were streamed: {train_views:?}");
    assert_eq!(train_views.uploads_in_step, 1, "{train_views:?}");
}

#[test]
fn a_budget_below_one_view_is_refused_before_training() {
    let dir = ScratchDir::new("target-budget");
    let scene = dir.join("data");
    write_dataset(&generate(&SyntheticConfig::small()), &scene).expect("dataset");
    let config = RunConfig {
        data: Some(scene),
        out: dir.join("run"),
        iterations: 4,
        sh_degree: 1,
        target_memory: Some(0),
        ..RunConfig::default()
    };
    let err = TrainingRun::start(config, RunOptions::default())
        .expect_err("a budget of 0 MiB is refused");
    let message = format!("{err:#}");
    assert!(message.contains("cannot hold one view"), "{message}");
    assert!(message.contains("--target-memory"), "{message}");
    assert!(message.contains("view_"), "the view is named: {message}");
    assert!(!dir.join("run").exists(), "refused before the run folder was made");
}
