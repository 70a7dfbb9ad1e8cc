//! A training step on a device that was lost fails with an error that says so, and the state read
//! before the loss (what a checkpoint holds) is intact: nothing panics, nothing saved is lost.
use trgs_core::fixtures::{SceneSpec, random_scene};
use trgs_render::{GpuContext, GpuError, Layer, RenderError};
use trgs_train::TrainSettings;
use trgs_train::Trainer;
use trgs_train::View;

#[test]
fn a_training_step_on_a_lost_device_is_an_error() {
    let ctx = GpuContext::new().expect("adapter");
    let scene = random_scene(&SceneSpec { planes: 1, ..SceneSpec::default() });
    let gaussians = scene.gaussians.cast::<f32>();
    let mut trainer =
        Trainer::new(&ctx, &gaussians, &scene.planes, TrainSettings::scaled(100), 1.0)
            .expect("trainer");
    let mut image = trainer
        .render(&scene.camera)
        .expect("render")
        .read_layer(&ctx, Layer::Color)
        .expect("readback");
    image.data.iter_mut().for_each(|v| *v *= 0.9);
    let view = View::new(scene.camera.clone(), image.quantised());
    trainer.train_step(&view).expect("a step on a working device");
    let saved = trainer.checkpoint(serde_json::Value::Null).expect("checkpoint");
    assert_eq!(saved.step, 1);

    ctx.device.destroy();

    let err = trainer.train_step(&view).expect_err("a step on a lost device");
    // The step failed in its render: a GPU error inside the renderer's own error type.
    let lost = err.chain().any(|e| {
        matches!(e.downcast_ref::<GpuError>(), Some(GpuError::Lost { .. }))
            || matches!(
                e.downcast_ref::<RenderError>(),
                Some(RenderError::Gpu(GpuError::Lost { .. }))
            )
    });
    assert!(lost, "{err:#}");
    assert!(format!("{err:#}").contains("the GPU device was lost"), "{err:#}");
    assert!(trainer.checkpoint(serde_json::Value::Null).is_err(), "nothing to read back");
    assert_eq!(saved.state.gaussians.len(), gaussians.len(), "the saved state is whole");
    assert!(saved.state.gaussians.means.iter().flatten().all(|v| v.is_finite()));
}
