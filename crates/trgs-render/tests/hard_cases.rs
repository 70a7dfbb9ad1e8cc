//! Hard cases on the GPU path: outputs stay finite and bad input is refused before any kernel.
use glam::DVec3;
use trgs_core::fixtures::{RoomDensity, RoomSpec, SceneSpec, random_scene, room_scene};
use trgs_core::pipeline::TILE_SIZE;
use trgs_core::scene::{
    Camera, Gaussians, Intrinsics, Material, Population, Pose, ReflectionPlane,
};
use trgs_render::{
    BackwardError, BackwardOptions, DeviceOptions, Frame, FrameImages, GpuContext, GpuScene, Layer,
    LayerGrads, RenderError, RenderOptions, Renderer,
};

fn ctx() -> GpuContext {
    let opts = DeviceOptions { poison_fresh_buffers: true, ..Default::default() };
    GpuContext::with_options(&opts).unwrap_or_else(|e| panic!("{e}"))
}

fn all_finite(f: &FrameImages) -> bool {
    [&f.color, &f.transmission, &f.depth, &f.mask, &f.alpha, &f.strength, &f.reflection]
        .iter()
        .all(|i| i.data.iter().all(|v| v.is_finite()))
}

#[test]
fn empty_scene_shows_the_background() {
    let ctx = ctx();
    let camera = Camera::new("c", Intrinsics::from_fov_x(1.0, 40, 30), Pose::default());
    let scene = GpuScene::upload(&ctx, &Gaussians::<f32>::empty(0), &[]).expect("empty is valid");
    let opts = RenderOptions { background: [0.25, 0.5, 0.75], ..Default::default() };
    let f = Renderer::new(&ctx)
        .render(&scene, &camera, &opts)
        .expect("render")
        .read_images(&ctx)
        .expect("readback");
    assert!(f.color.data.chunks(3).all(|p| p == [0.25, 0.5, 0.75]));
    assert!(f.alpha.data.iter().all(|&a| a == 0.0));
}

#[test]
fn one_pixel_image_and_gaussians_behind_the_camera() {
    let ctx = ctx();
    let s = random_scene(&SceneSpec {
        width: 1,
        height: 1,
        planes: 1,
        gaussians: 50,
        ..SceneSpec::default()
    });
    let scene = GpuScene::upload(&ctx, &s.gaussians.cast(), &s.planes).expect("valid");
    let renderer = Renderer::new(&ctx);
    let f = renderer.render(&scene, &s.camera, &RenderOptions::default()).expect("render");
    assert!(all_finite(&f.read_images(&ctx).expect("readback")));
    // Turn the camera around: everything is behind it.
    let mut back = s.camera.clone();
    back.pose = Pose::look_at(s.camera.pose.centre(), 2.0 * s.camera.pose.centre(), DVec3::Y);
    let f = renderer.render(&scene, &back, &RenderOptions::default()).expect("render");
    assert_eq!(f.key_count(), 0);
}

#[test]
fn camera_behind_or_on_the_plane_skips_the_mirrored_pass() {
    let ctx = ctx();
    let s = random_scene(&SceneSpec { planes: 1, gaussians: 200, ..SceneSpec::default() });
    // An axis-aligned plane z = 0 facing +z, so that "on the plane" is exact.
    let p = ReflectionPlane::new(DVec3::ZERO, DVec3::Z, DVec3::X, 2.4, 1.8, Material::Glass);
    let scene =
        GpuScene::upload(&ctx, &s.gaussians.cast(), std::slice::from_ref(&p)).expect("valid");
    let renderer = Renderer::new(&ctx);
    for (name, eye) in [("behind", DVec3::new(0.2, 0.1, -3.0)), ("on", DVec3::new(0.3, 0.2, 0.0))] {
        let mut cam = s.camera.clone();
        cam.pose = Pose::look_at(eye, DVec3::new(0.0, 0.5, 1.0), DVec3::Y);
        let f = renderer.render(&scene, &cam, &RenderOptions::default()).expect("render");
        assert!(!f.plane_rendered(0), "{name}: the mirrored pass must not run");
        let img = f.read_images(&ctx).expect("readback");
        assert!(all_finite(&img), "{name}");
        assert_eq!(img.color.data, img.transmission.data, "{name}: C = C_t");
    }
}

#[test]
fn a_plane_switched_off_does_not_hide_the_plane_behind_it() {
    let ctx = ctx();
    let s = random_scene(&SceneSpec {
        planes: 1,
        gaussians: 300,
        width: 64,
        height: 48,
        ..SceneSpec::default()
    });
    let back = s.planes[0];
    // The same pane moved a third of the way towards the camera: it covers the back one.
    let mut front = back;
    front.centre += (s.camera.pose.centre() - back.centre) / 3.0;
    let g = s.gaussians.cast();
    let renderer = Renderer::new(&ctx);
    let images = |planes: &[ReflectionPlane], enabled: Vec<bool>| {
        let scene = GpuScene::upload(&ctx, &g, planes).expect("valid");
        let options = RenderOptions { enabled_planes: enabled, ..Default::default() };
        renderer
            .render(&scene, &s.camera, &options)
            .expect("render")
            .read_images(&ctx)
            .expect("readback")
    };
    let both = images(&[back, front], vec![true, true]);
    let front_off = images(&[back, front], vec![true, false]);
    let back_only = images(&[back], vec![true]);
    // With both on, the front pane takes pixels the back one has alone.
    let hits = |f: &FrameImages, k: u32| f.hit.data.iter().filter(|&&h| h == k + 1).count();
    assert!(hits(&back_only, 0) > 20, "the back pane is in view");
    assert!(hits(&both, 1) > 0 && hits(&both, 0) < hits(&back_only, 0));
    // Switched off, the front pane is as if it were not in the scene.
    assert_eq!(front_off.hit.data, back_only.hit.data);
    assert_eq!(front_off.color.data, back_only.color.data);
    assert_eq!(front_off.reflection.data, back_only.reflection.data);
    assert_eq!(front_off.strength.data, back_only.strength.data);
}

#[test]
fn extreme_scales_stay_finite() {
    let ctx = ctx();
    let mut s = random_scene(&SceneSpec { planes: 1, gaussians: 60, ..SceneSpec::default() });
    for (i, ls) in s.gaussians.log_scales.iter_mut().enumerate() {
        *ls = match i % 4 {
            0 => [-18.0; 3],          // 1.5e-8: a point
            1 => [7.0, 7.0, 7.0],     // 1e3: larger than the scene
            2 => [3.0, -18.0, -18.0], // a needle
            _ => [2.0, 2.0, -18.0],   // a disc
        };
    }
    let scene = GpuScene::upload(&ctx, &s.gaussians.cast(), &s.planes).expect("valid");
    let f =
        Renderer::new(&ctx).render(&scene, &s.camera, &RenderOptions::default()).expect("render");
    assert!(all_finite(&f.read_images(&ctx).expect("readback")));
}

#[test]
fn huge_gaussians_extreme_logits_are_culled_alike_on_gpu_and_twin() {
    let ctx = ctx();
    let renderer = Renderer::new(&ctx);
    let s = random_scene(&SceneSpec { planes: 0, gaussians: 60, ..SceneSpec::default() });
    let mut g = s.gaussians.clone();
    let base = g.len();
    let ahead = s.camera.pose.direction_to_world(DVec3::Z) * 3.0 + s.camera.pose.centre();
    // Scales the f32 determinant cannot hold (culled on the GPU), and an opacity logit whose f32
    // sigmoid is exactly zero (log(0) in the opacity cull).
    for (log_scale, logit) in [(20.0, 1.0), (50.0, 1.0), (100.0, 1.0), (-1.0, -200.0)] {
        let sh = vec![[0.5; 3]; g.sh_coeffs()];
        g.push(
            ahead.to_array(),
            [1.0, 0.0, 0.0, 0.0],
            [log_scale; 3],
            logit,
            &sh,
            Population::Primary,
        );
    }
    let view = trgs_core::scene::ViewTransform::from(&s.camera.pose);
    let k = &s.camera.intrinsics;
    let grid = trgs_core::pipeline::TileGrid::new(k.width, k.height);
    let p = trgs_core::reference::project(
        &g,
        &view,
        k,
        trgs_core::reference::ProjectionFilter::All,
        &grid.full(),
        0.2,
    );
    assert!((base..g.len()).all(|i| !p.visible[i]), "the twin culls them");
    let opts = RenderOptions::default();
    let without = GpuScene::upload(&ctx, &s.gaussians.cast(), &[]).expect("valid");
    let with = GpuScene::upload(&ctx, &g.cast(), &[]).expect("valid");
    let a = renderer.render(&without, &s.camera, &opts).expect("render");
    let b = renderer.render(&with, &s.camera, &opts).expect("render");
    assert_eq!(a.key_count(), b.key_count(), "the GPU culls them too");
    let (ia, ib) = (a.read_images(&ctx).expect("readback"), b.read_images(&ctx).expect("readback"));
    assert!(all_finite(&ib));
    assert_eq!(ia.color.data, ib.color.data);
    // A reflection intensity f32 cannot carry through compose is refused by name.
    let mut r = g.cast::<f32>();
    r.log_reflections[5] = 100.0;
    let err = GpuScene::upload(&ctx, &r, &[]).expect_err("log_reflection 100");
    assert!(err.to_string().contains("Gaussian 5: log_reflection"), "{err}");
}

#[test]
fn non_finite_input_is_refused_with_its_name() {
    let ctx = ctx();
    let s = random_scene(&SceneSpec::default());
    let mut g: Gaussians<f32> = s.gaussians.cast();
    g.log_scales[7][1] = f32::NAN;
    let err = GpuScene::upload(&ctx, &g, &s.planes).expect_err("NaN must be refused");
    assert_eq!(err.to_string(), "Gaussian 7: log_scale is not finite (NaN)");
    let mut g: Gaussians<f32> = s.gaussians.cast();
    g.means[3][0] = f32::INFINITY;
    let err = GpuScene::upload(&ctx, &g, &s.planes).expect_err("Inf must be refused");
    assert!(err.to_string().starts_with("Gaussian 3: mean"), "{err}");
    let scene = GpuScene::upload(&ctx, &s.gaussians.cast(), &s.planes).expect("valid");
    let mut cam = s.camera.clone();
    cam.intrinsics.fx = f64::NAN;
    let err = Renderer::new(&ctx)
        .render(&scene, &cam, &RenderOptions::default())
        .expect_err("bad camera");
    assert!(err.to_string().contains("random"), "{err}");
    cam.intrinsics = Intrinsics { width: 0, ..s.camera.intrinsics };
    assert!(Renderer::new(&ctx).render(&scene, &cam, &RenderOptions::default()).is_err());
}

#[test]
fn half_a_million_gaussians_render() {
    // Plain context (no poison fill: 500k Gaussians make large buffers).
    let ctx = GpuContext::new().unwrap_or_else(|e| panic!("{e}"));
    let s = room_scene(&RoomSpec {
        seed: 3,
        gaussians: 500_000,
        planes: 2,
        width: 128,
        height: 96,
        sh_degree: 3,
        density: RoomDensity::Uniform,
    });
    let scene = GpuScene::upload(&ctx, &s.gaussians.cast(), &s.planes).expect("valid");
    let f =
        Renderer::new(&ctx).render(&scene, &s.camera, &RenderOptions::default()).expect("render");
    let img = f.read_images(&ctx).expect("readback");
    assert!(all_finite(&img));
    let limit = ctx.binding_limit();
    eprintln!(
        "500k Gaussians: {} keys, frame memory {:.1} MiB, binding limit {} MiB, SH buffer {:.1} MiB",
        f.key_count(),
        f.memory_bytes() as f64 / 1048576.0,
        limit / 1048576,
        (s.gaussians.sh.len() * 12) as f64 / 1048576.0
    );
    assert!(img.alpha.data.iter().filter(|&&a| a > 0.9).count() > 128 * 96 / 2);
}

#[test]
fn frames_over_the_binding_limit_are_refused_with_a_clear_error() {
    let ctx = GpuContext::new().unwrap_or_else(|e| panic!("{e}"));
    let limit = ctx.binding_limit();
    let mut renderer = Renderer::new(&ctx);
    let s = random_scene(&SceneSpec { planes: 0, gaussians: 1, ..SceneSpec::default() });
    // An image whose per-pixel layers alone exceed one binding: refused before any kernel.
    let side = ((limit / 16) as f64).sqrt() as u32 + 1;
    let mut cam = s.camera.clone();
    cam.intrinsics = Intrinsics::from_fov_x(1.0, side, side);
    let scene = GpuScene::upload(&ctx, &s.gaussians.cast(), &[]).expect("valid");
    let err = renderer.render(&scene, &cam, &RenderOptions::default()).expect_err("too large");
    assert!(err.to_string().contains("image layers"), "{err}");
    // A key list over its two pages: Gaussians that each cover every tile of a 2048x2048
    // image. The pages are set to eight Gaussians' keys each (at the binding limit it takes
    // the same code path, with two thousand Gaussians and 67M keys counted first).
    let (w, h) = (2048u32, 2048u32);
    let tiles = u64::from(w / TILE_SIZE) * u64::from(h / TILE_SIZE);
    renderer.set_key_page_len(8 * tiles as u32);
    let n = (2 * u64::from(renderer.key_page_len()) / tiles + 1) as usize;
    let mut g = Gaussians::<f32>::empty(0);
    for i in 0..n {
        let mean = [0.0, 0.0, 5.0 + 1e-4 * i as f32];
        g.push(mean, [1.0, 0.0, 0.0, 0.0], [3.0; 3], 4.0, &[[0.5; 3]], Population::Primary);
    }
    let big = GpuScene::upload(&ctx, &g, &[]).expect("valid");
    let wide = Camera::new("wide", Intrinsics::from_fov_x(1.0, w, h), Pose::default());
    // Into a frame that holds an earlier, smaller render: the failure comes after the frame
    // was reset, and must leave it "not rendered", not the old buffers under the new size.
    let small = Camera::new("small", Intrinsics::from_fov_x(1.0, 8, 6), Pose::default());
    let mut frame = Frame::default();
    renderer.render_into(&big, &small, &RenderOptions::default(), &mut frame).expect("small");
    let old_grads = LayerGrads::zeros(&ctx, &frame).expect("allocation");
    let err = renderer
        .render_into(&big, &wide, &RenderOptions::default(), &mut frame)
        .expect_err("too many keys");
    let text = err.to_string();
    assert!(text.contains("\"wide\"") && text.contains("tile keys"), "{text}");
    assert_eq!(
        frame.read_layer(&ctx, Layer::Color).expect("readback").data.len(),
        0,
        "no stale image"
    );
    let err = renderer
        .backward(&big, &mut frame, &old_grads, &BackwardOptions::default())
        .expect_err("nothing rendered");
    assert!(matches!(err, BackwardError::NotRendered), "{err}");
}

#[test]
fn bad_options_too_many_tiles_and_stale_gradients_are_errors() {
    let ctx = ctx();
    let renderer = Renderer::new(&ctx);
    let s = random_scene(&SceneSpec { planes: 1, gaussians: 40, ..SceneSpec::default() });
    let scene = GpuScene::upload(&ctx, &s.gaussians.cast(), &s.planes).expect("valid");
    let bad = [
        (RenderOptions { near: f64::NAN, ..Default::default() }, "near"),
        (RenderOptions { near: 0.0, ..Default::default() }, "near"),
        (RenderOptions { near: -1.0, ..Default::default() }, "near"),
        (RenderOptions { background: [0.0, f32::NAN, 0.0], ..Default::default() }, "background"),
    ];
    for (options, what) in bad {
        let err = renderer.render(&scene, &s.camera, &options).expect_err(what);
        assert!(err.to_string().contains(what), "{err}");
    }
    // More tiles along one axis than a dispatch dimension holds.
    let most = ctx.device.limits().max_compute_workgroups_per_dimension;
    let mut strip = s.camera.clone();
    strip.intrinsics = Intrinsics::from_fov_x(1.0, (most + 1) * TILE_SIZE, 1);
    let err = renderer.render(&scene, &strip, &RenderOptions::default()).expect_err("tiles");
    assert!(matches!(err, RenderError::TooManyTiles { .. }), "{err}");
    // Gradients made for another frame size are refused: a smaller one would be read out of
    // range, a transposed one (as many pixels) at the wrong pixels; so are buffers made by hand
    // too short for the frame.
    let render_at = |w: u32, h: u32, frame: &mut Frame| {
        let mut cam = s.camera.clone();
        cam.intrinsics = Intrinsics::from_fov_x(1.0, w, h);
        renderer.render_into(&scene, &cam, &RenderOptions::default(), frame).expect("render");
    };
    let backward = |frame: &mut Frame, grads: &LayerGrads| {
        renderer.backward(&scene, frame, grads, &BackwardOptions::default()).expect_err("stale")
    };
    let mut frame = Frame::default();
    for (w, h) in [(8, 6), (6, 8)] {
        render_at(w, h, &mut frame);
        let grads = LayerGrads::zeros(&ctx, &frame).expect("allocation");
        render_at(8, 6, &mut frame);
        if (w, h) != (8, 6) {
            let err = backward(&mut frame, &grads);
            assert!(matches!(err, BackwardError::GradsForAnotherSize { .. }), "{err}");
        }
    }
    let mut grads = LayerGrads::zeros(&ctx, &frame).expect("allocation");
    render_at(16, 12, &mut frame);
    grads.size = (16, 12);
    let err = backward(&mut frame, &grads);
    assert!(matches!(err, BackwardError::GradsTooSmall { .. }), "{err}");
}
