//! `Trainer::train_step_then` calls its hook after the step's update and before the step's
//! maintenance: an evaluation there sees the model the step made, not an opacity reset.
use trgs_core::scene::Attribute;
use trgs_render::GpuContext;
use trgs_synthetic::{SyntheticConfig, generate, write_dataset};
use trgs_train::TrainSettings;
use trgs_train::Trainer;
use trgs_train::densify::{ClassicSettings, Densification};
use trgs_train::{InitialShape, SeedPoint, gaussians_from_points};
use trgs_train::{LoadOptions, Resolution, TrainingData};

#[test]
fn hook_runs_after_the_update_and_before_the_opacity_reset() {
    let dir = trgs_core::scratch::ScratchDir::new("evaluation-point");
    let scene = generate(&SyntheticConfig::small());
    write_dataset(&scene, &dir).expect("write the dataset");
    let data = TrainingData::load(
        &trgs_core::io::SceneFolder::open(&dir).expect("open the dataset"),
        &LoadOptions::at(Resolution::Original),
    )
    .expect("load the dataset");
    let seeds: Vec<SeedPoint> =
        data.points.iter().map(|&(position, color)| SeedPoint { position, color }).collect();
    let gaussians = gaussians_from_points(&seeds, 0, InitialShape::CLASSIC);
    let ctx = GpuContext::new().expect("adapter");
    let mut settings = TrainSettings::scaled(100);
    settings.sh_degree = 0;
    let mut trainer = Trainer::new(&ctx, &gaussians, &[], settings, data.extent).expect("trainer");
    // An opacity reset at step 3 and no densification before the end.
    let mut densify = ClassicSettings::scaled(100);
    (densify.from, densify.until, densify.every, densify.opacity_reset_every) = (50, 60, 50, 3);
    trainer.set_densification(&Densification::Classic(densify)).expect("densification");
    let cap = (0.01f32 / 0.99).ln();
    let max_logit = |t: &Trainer| {
        t.gaussians().expect("readback").opacity_logits.iter().copied().fold(f32::MIN, f32::max)
    };
    for v in &data.train[..2] {
        trainer.train_step(v).expect("step");
    }
    let before = trainer.gaussians().expect("readback").means;
    let mut seen = None;
    trainer
        .train_step_then(&data.train[2], |t| {
            seen = Some((t.step, max_logit(t), t.gaussians().expect("readback").means != before));
            Ok(())
        })
        .expect("step");
    let (step, logit, moved) = seen.expect("the hook ran");
    assert_eq!(step, 3, "the hook sees the step advanced");
    assert!(moved, "the hook sees the step's update");
    assert!(logit > cap + 1.0, "the hook ran after the reset: largest logit {logit}");
    assert!(max_logit(&trainer) <= cap, "the reset did not follow the hook");
    // The reset clears the opacities' moments only.
    let state = trainer.read_state().expect("readback");
    let opacity = Attribute::OpacityLogits;
    assert!(state.m[opacity].iter().chain(&state.v[opacity]).all(|&x| x == 0.0));
    assert!(state.m[Attribute::Means].iter().any(|&x| x != 0.0), "the means' moments stay");
}
