//! End-to-end training on the small synthetic glass scene (64x48, 12 views) written to disk and
//! loaded back as a user's scene folder would be: stage 1 improves the test views, the plane
//! fitted from the masks lies near the true pane, and stages 2 and 3 keep every parameter finite.
use trgs_core::metrics::psnr;
use trgs_render::{GpuContext, Layer};
use trgs_synthetic::{SyntheticConfig, generate, write_dataset};
use trgs_train::TrainSettings;
use trgs_train::Trainer;
use trgs_train::densify::{ClassicSettings, Densification};
use trgs_train::{InitialShape, SeedPoint, gaussians_from_points};
use trgs_train::{LoadOptions, Resolution, TrainingData};
use trgs_train::{PlaneInitSettings, initialise_planes};

fn test_psnr(trainer: &Trainer, data: &TrainingData) -> f64 {
    let mut sum = 0.0;
    for v in &data.test {
        let frame = trainer.render(&v.camera).expect("render");
        let c = frame.read_layer(trainer.context(), Layer::Color).expect("readback");
        sum += psnr(&c, &v.image.to_f32()).expect("same size");
    }
    sum / data.test.len() as f64
}

#[test]
fn small_scene_trains_and_finds_its_plane() {
    let dir = trgs_core::scratch::ScratchDir::new("train-small");
    let scene = generate(&SyntheticConfig::small());
    write_dataset(&scene, &dir).expect("write the dataset");
    let data = TrainingData::load(
        &trgs_core::io::SceneFolder::open(&dir).expect("open the dataset"),
        &LoadOptions::at(Resolution::Original),
    )
    .expect("load the dataset");
    assert_eq!(data.materials.len(), 1, "one glass label");
    let seeds: Vec<SeedPoint> =
        data.points.iter().map(|&(position, color)| SeedPoint { position, color }).collect();
    let gaussians = gaussians_from_points(&seeds, 1, InitialShape::CLASSIC);
    let ctx = GpuContext::new().expect("adapter");
    let iterations = 150;
    let mut settings = TrainSettings::scaled(iterations);
    settings.sh_degree = 1;
    settings.stage1 = 60;
    settings.stage2 = 30;
    let mut trainer = Trainer::new(&ctx, &gaussians, &[], settings, data.extent).expect("trainer");
    let mut densify = ClassicSettings::scaled(iterations);
    densify.every = 20;
    densify.from = 20;
    densify.until = 100;
    trainer.set_densification(&Densification::Classic(densify)).expect("densification");
    let before = test_psnr(&trainer, &data);
    let mut rng = trgs_core::rng::Rng::new(1);
    let mut limits = Vec::new();
    while trainer.step < iterations {
        for v in &data.train {
            if trainer.step == trainer.settings.stage1 {
                let after_stage1 = test_psnr(&trainer, &data);
                eprintln!("test PSNR {before:.2} dB at the start, {after_stage1:.2} after stage 1");
                assert!(after_stage1 > before + 1.0, "stage 1 did not learn");
                let init = initialise_planes(
                    &trainer.gaussians().expect("readback"),
                    &data.train,
                    &data.materials,
                    data.extent,
                    &PlaneInitSettings::default(),
                    &mut rng,
                );
                assert!(init.failed.is_empty(), "{:?}", init.failed);
                let (got, truth) = (&init.planes[0], &scene.planes[0]);
                let angle = got.unit_normal().dot(truth.unit_normal()).clamp(-1.0, 1.0).acos();
                let off = got.centre.distance(truth.centre) / truth.width.hypot(truth.height);
                eprintln!(
                    "plane: normal {:.2} deg off, centre {:.1}% of the size",
                    angle.to_degrees(),
                    100.0 * off
                );
                // After 60 steps at 64x48 the Gaussians on the frame are coarse, and the GPU's
                // float-atomic order varies the trajectory: the normal has come out 1.7 to 6.3
                // degrees off over runs. The 2-degree bar is measured on the 256x192 scene.
                assert!(angle.to_degrees() < 10.0, "normal {:.2} deg off", angle.to_degrees());
                assert!(off < 0.1, "centre {off:.3} of the size off");
                trainer
                    .add_planes(&init.planes, &init.offset_limits, &init.glass)
                    .expect("add planes");
                limits = init.offset_limits;
            }
            if trainer.step == iterations {
                break;
            }
            let stats = trainer.train_step(v).expect("step");
            assert!(stats.loss.is_finite());
        }
    }
    let g = trainer.gaussians().expect("readback");
    assert!(g.means.iter().flatten().chain(g.log_scales.iter().flatten()).all(|v| v.is_finite()));
    let p = &trainer.planes()[0];
    assert!(p.centre.is_finite() && p.normal.length() > 0.0 && p.normal.is_finite());
    assert!(p.centre.distance(scene.planes[0].centre) < 0.2 * data.extent);
    // The plane's Adam counts its own steps (bias correction from its creation at step 60).
    let ck = trainer.checkpoint(serde_json::Value::Null).expect("readback");
    assert_eq!(ck.plane_moments[0].steps, iterations - 60);
    // The masks pinned the plane's offset, the checkpoint keeps the limit, and training kept it.
    let limit = limits[0].expect("the masks set an offset limit");
    assert_eq!(ck.plane_moments[0].offset_limit, Some(limit));
    let off = (p.centre - glam::DVec3::from_array(limit.anchor)).dot(p.unit_normal());
    assert!(off.abs() <= limit.tolerance + 1e-9, "offset {off} beyond {}", limit.tolerance);
    let after = test_psnr(&trainer, &data);
    eprintln!("test PSNR {after:.2} dB after {iterations} steps");
    assert!(after > before + 1.0);
}
