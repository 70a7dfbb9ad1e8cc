//! GPU failures come back as errors from the call that met them, not as a panic: a lost device,
//! and an operation wgpu refuses (here a buffer over the device's size limit, which is how an
//! out-of-memory frame or upload also reaches the caller: through the same error scopes).
//! Each test makes its own device, since one of them destroys it.
use trgs_core::fixtures::{SceneSpec, random_scene};
use trgs_render::toolkit::gpu::{self, ErrorScopes};
use trgs_render::{
    BackwardError, DisplayError, DisplayTarget, GpuContext, GpuError, GpuScene, Layer, RenderError,
    RenderOptions, Renderer, UploadError,
};

fn context() -> GpuContext {
    GpuContext::new().expect("a Vulkan adapter (lavapipe on CI)")
}

#[test]
fn a_lost_device_fails_renders_uploads_and_readbacks_with_an_error() {
    let ctx = context();
    let scene = random_scene(&SceneSpec { planes: 1, ..SceneSpec::default() });
    let gaussians = scene.gaussians.cast::<f32>();
    let gpu_scene = GpuScene::upload(&ctx, &gaussians, &scene.planes).expect("upload");
    let renderer = Renderer::new(&ctx);
    let options = RenderOptions::default();
    let frame = renderer.render(&gpu_scene, &scene.camera, &options).expect("render");
    let before = frame.read_layer(&ctx, Layer::Color).expect("readback before the loss");
    assert!(before.data.iter().any(|&v| v > 0.0), "the scene renders something");

    ctx.device.destroy();

    match renderer.render(&gpu_scene, &scene.camera, &options) {
        Err(RenderError::Gpu(GpuError::Lost { what, .. })) => {
            assert!(!what.is_empty(), "the error says what was being done");
        }
        other => panic!("render after the loss: {other:?}"),
    }
    assert!(matches!(frame.read_layer(&ctx, Layer::Color), Err(GpuError::Lost { .. })));
    assert!(matches!(frame.read_images(&ctx), Err(GpuError::Lost { .. })));
    assert!(matches!(gpu_scene.read(&ctx), Err(GpuError::Lost { .. })));
    assert!(matches!(gpu::wait_for_gpu(&ctx, "nothing"), Ok(()) | Err(GpuError::Lost { .. })));
    assert_eq!(ctx.lost().as_deref(), Some("Destroyed"), "the context knows why");
    // Uploading and displaying go through the same scopes and waits.
    let upload = GpuScene::upload(&ctx, &gaussians, &scene.planes);
    assert!(matches!(upload, Err(UploadError::Gpu(GpuError::Lost { .. }))), "{upload:?}");
    // Lavapipe still hands out the texture of a lost device, NVIDIA's driver refuses it: either
    // way nothing that uses the device succeeds.
    match DisplayTarget::new(&ctx, frame.width(), frame.height()) {
        Ok(target) => {
            let shown = renderer.display(&frame, Layer::Color, [0.1, 10.0], &target);
            assert!(matches!(shown, Err(DisplayError::Gpu(GpuError::Lost { .. }))), "{shown:?}");
            assert!(matches!(target.read_rgba(&ctx), Err(GpuError::Lost { .. })));
        }
        Err(GpuError::Lost { what, .. }) => assert!(what.contains("display target"), "{what}"),
        Err(other) => panic!("a display target on a lost device: {other:?}"),
    }
    // The message names the failure and the operation for a person.
    let message = frame.read_layer(&ctx, Layer::Color).expect_err("lost").to_string();
    assert_eq!(
        message,
        "the GPU device was lost while reading back a buffer (Destroyed); create a new \
         GpuContext to go on"
    );
}

#[test]
fn an_operation_wgpu_refuses_is_an_error_of_the_call() {
    let ctx = context();
    let too_big = ctx.device.limits().max_buffer_size.saturating_add(1 << 20);
    let scopes = ErrorScopes::open(&ctx, "allocating a buffer over the limit");
    let _buffer = gpu::storage(&ctx, "trgs.test.too_big", too_big);
    match scopes.close() {
        Err(GpuError::Rejected { what, detail }) => {
            assert_eq!(what, "allocating a buffer over the limit");
            assert!(!detail.is_empty());
        }
        other => panic!("expected a refused allocation, got {other:?}"),
    }
    // Scopes dropped unclosed (an early return) pop themselves in the order wgpu requires, with
    // or without an error caught.
    {
        let _dropped = ErrorScopes::open(&ctx, "dropped with an error");
        let _buffer = gpu::storage(&ctx, "trgs.test.too_big", too_big);
    }
    drop(ErrorScopes::open(&ctx, "dropped empty"));
    // Scopes that caught nothing close cleanly, and nest.
    let outer = ErrorScopes::open(&ctx, "outer");
    let inner = ErrorScopes::open(&ctx, "inner");
    let _small = gpu::storage(&ctx, "trgs.test.small", 256);
    assert_eq!(inner.close(), Ok(()));
    assert_eq!(outer.close(), Ok(()));
    // The device is still usable after a caught error: a frame renders.
    let scene = random_scene(&SceneSpec::default());
    let gpu_scene =
        GpuScene::upload(&ctx, &scene.gaussians.cast::<f32>(), &scene.planes).expect("upload");
    let frame = Renderer::new(&ctx)
        .render(&gpu_scene, &scene.camera, &RenderOptions::default())
        .expect("render after a caught error");
    assert!(frame.read_layer(&ctx, Layer::Color).is_ok());
    // BackwardError carries GPU failures too (checked by type: this must compile).
    let _: fn(GpuError) -> BackwardError = BackwardError::from;
}
