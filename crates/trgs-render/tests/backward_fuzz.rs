//! Fuzzing the GPU backward: random finite scenes with extreme attributes (scales from 1e-5 to
//! 50, opacities saturated both ways, Gaussians behind and at the camera, huge SH, planes at any
//! angle including edge-on and behind the camera) and random finite upstream gradients up to
//! 1e3 never produce a NaN or Inf gradient; non-finite inputs are rejected with an error before
//! any kernel runs.
use trgs_core::fixtures::{Scene, random_scene};
use trgs_core::reference::FrameGrads;
use trgs_core::rng::Rng;
use trgs_core::scene::Gaussians;
use trgs_render::{
    BackwardOptions, GpuContext, GpuScene, LayerGrads, LayerGradsError, RenderOptions, Renderer,
};

mod common;

/// A random scene whose attributes are pushed to their extremes.
fn wild_scene(seed: u64, width: u32, height: u32) -> Scene {
    let mut rng = Rng::new(seed);
    let mut spec = common::spec(seed, 300, (seed % 3) as usize, rng.range(0.0, 95.0));
    (spec.width, spec.height) = (width, height);
    let mut s = random_scene(&spec);
    let eye = s.camera.pose.centre();
    let g = &mut s.gaussians;
    for i in 0..g.len() {
        match rng.below(8) {
            0 => g.log_scales[i] = [rng.range(-12.0, -9.0); 3],
            1 => {
                g.log_scales[i] = [rng.range(2.0, 4.0), rng.range(-12.0, 4.0), rng.range(-3.0, 0.0)]
            }
            2 => {
                g.means[i] = (eye
                    + 0.05 * glam::DVec3::new(rng.normal(), rng.normal(), rng.normal()))
                .to_array()
            }
            3 => g.means[i] = (2.0 * eye - glam::DVec3::from_array(g.means[i])).to_array(),
            4 => g.rotations[i] = [1e-6, rng.normal() * 1e-6, 0.0, 1e-6],
            _ => {}
        }
        g.opacity_logits[i] = rng.range(-25.0, 25.0);
        g.mask_logits[i] = rng.range(-30.0, 30.0);
        g.log_reflections[i] = rng.range(-6.0, 6.0);
    }
    for c in &mut g.sh {
        for v in c.iter_mut() {
            *v *= rng.range(0.0, 40.0);
        }
    }
    s
}

fn random_grads(rng: &mut Rng, w: u32, h: u32, planes: usize) -> FrameGrads {
    FrameGrads::filled(w, h, planes, |im| {
        let scale = 10f64.powf(rng.range(-3.0, 3.0));
        for v in &mut im.data {
            *v = scale * rng.range(-1.0, 1.0);
        }
    })
}

fn all_finite(g: &Gaussians<f32>) -> bool {
    let flat3 = |v: &[[f32; 3]]| v.iter().flatten().all(|x| x.is_finite());
    flat3(&g.means)
        && flat3(&g.log_scales)
        && flat3(&g.sh)
        && g.rotations.iter().flatten().all(|x| x.is_finite())
        && g.opacity_logits.iter().all(|x| x.is_finite())
        && g.mask_logits.iter().all(|x| x.is_finite())
        && g.log_reflections.iter().all(|x| x.is_finite())
}

#[test]
fn random_finite_inputs_give_finite_gradients() {
    let ctx = GpuContext::new().expect("adapter");
    let renderer = Renderer::new(&ctx);
    let mut rng = Rng::new(0xf022);
    for seed in 0..16u64 {
        let (w, h) = if seed == 5 { (1, 1) } else { (40, 30) };
        let scene = wild_scene(seed, w, h);
        let gpu_scene =
            GpuScene::upload(&ctx, &scene.gaussians.cast::<f32>(), &scene.planes).expect("finite");
        let options = RenderOptions { depth_variance: seed % 2 == 0, ..Default::default() };
        let mut frame = renderer.render(&gpu_scene, &scene.camera, &options).expect("render");
        let grads = random_grads(&mut rng, w, h, scene.planes.len());
        let layer_grads = LayerGrads::upload(&ctx, &frame, &grads).expect("finite");
        let block = seed % 4 == 1;
        let bwd = BackwardOptions { block_reflection_to_gaussians: block, profile: false };
        let out = renderer.backward(&gpu_scene, &mut frame, &layer_grads, &bwd).expect("backward");
        let g = out.gaussians.read(&ctx).expect("readback");
        assert!(all_finite(&g), "seed {seed}: a Gaussian gradient is not finite");
        for p in &out.planes.read(&ctx).expect("plane readback") {
            let v = [p.centre.to_array(), p.normal.to_array(), [p.r0_logit; 3]];
            assert!(v.iter().flatten().all(|x| x.is_finite()), "seed {seed}: plane gradient {p:?}");
        }
    }
}

#[test]
fn empty_scene_has_empty_gradients() {
    let ctx = GpuContext::new().expect("adapter");
    let renderer = Renderer::new(&ctx);
    let scene = random_scene(&common::spec(3, 0, 1, 20.0));
    let gpu_scene = GpuScene::upload(&ctx, &Gaussians::<f32>::empty(3), &scene.planes).expect("ok");
    let mut frame =
        renderer.render(&gpu_scene, &scene.camera, &RenderOptions::default()).expect("render");
    let grads = LayerGrads::zeros(&ctx, &frame).expect("allocation");
    let out = renderer.backward(&gpu_scene, &mut frame, &grads, &BackwardOptions::default());
    let out = out.expect("backward");
    assert!(out.gaussians.read(&ctx).expect("readback").is_empty());
    assert_eq!(out.planes.read(&ctx).expect("plane readback").len(), 1);
}

#[test]
fn non_finite_inputs_are_rejected_before_any_kernel() {
    let ctx = GpuContext::new().expect("adapter");
    let renderer = Renderer::new(&ctx);
    let scene = random_scene(&common::spec(4, 50, 1, 20.0));
    let mut bad = scene.gaussians.cast::<f32>();
    bad.means[7][1] = f32::NAN;
    let err = GpuScene::upload(&ctx, &bad, &scene.planes).expect_err("NaN mean");
    assert!(err.to_string().contains("Gaussian 7"), "{err}");

    let gpu_scene =
        GpuScene::upload(&ctx, &scene.gaussians.cast::<f32>(), &scene.planes).expect("finite");
    let frame = renderer.render(&gpu_scene, &scene.camera, &RenderOptions::default()).expect("ok");
    let mut rng = Rng::new(1);
    let (w, h) = (frame.width(), frame.height());
    let mut grads = random_grads(&mut rng, w, h, 1);
    grads.depth.data[5] = f64::INFINITY;
    match LayerGrads::upload(&ctx, &frame, &grads) {
        Err(LayerGradsError::NonFinite { layer: "depth", x: 5, y: 0, .. }) => {}
        other => panic!("expected a non-finite depth gradient error, got {other:?}"),
    }
    let mut small = random_grads(&mut rng, w / 2, h, 1);
    small.planes.clear();
    assert!(LayerGrads::upload(&ctx, &frame, &small).is_err(), "wrong plane count or size");

    let mut camera = scene.camera.clone();
    camera.pose.translation.x = f64::NAN;
    assert!(renderer.render(&gpu_scene, &camera, &RenderOptions::default()).is_err());
}
