//! Hard cases of the CPU reference: every output (and every gradient) stays finite, or the input
//! is rejected with an error that names what is wrong.
use glam::DVec3;
use trgs_core::fixtures::{Scene, SceneSpec, random_scene};
use trgs_core::pipeline::RenderSettings;
use trgs_core::reference::{BackwardOptions, Frame, FrameGrads, backward, render};
use trgs_core::scene::InvalidInput;
use trgs_core::{Camera, Image, Intrinsics, Pose};

fn all_finite(img: &Image<f64>) -> bool {
    img.data.iter().all(|v| v.is_finite())
}

/// Render and backpropagate a loss of ones on every layer; assert everything is finite.
fn render_finite(scene: &Scene) -> Frame {
    let settings = RenderSettings::default();
    let f = render(&scene.gaussians, &scene.planes, &scene.camera, &settings).expect("valid input");
    for (name, img) in [
        ("color", &f.color),
        ("transmission", &f.transmission),
        ("depth", &f.depth),
        ("depth_variance", &f.depth_variance),
        ("mask", &f.mask),
        ("alpha", &f.alpha),
        ("strength_raw", &f.strength_raw),
        ("strength", &f.strength),
        ("reflection", &f.reflection),
    ] {
        assert!(all_finite(img), "layer {name} is not finite");
    }
    let g = FrameGrads::filled(f.width(), f.height(), f.planes.len(), |img| img.data.fill(1.0));
    let gr = backward(
        &scene.gaussians,
        &scene.planes,
        &scene.camera,
        &settings,
        &f,
        &g,
        &BackwardOptions::default(),
    )
    .expect("valid input");
    let gg = &gr.gaussians;
    let flat = gg
        .means
        .iter()
        .flatten()
        .chain(gg.rotations.iter().flatten())
        .chain(gg.log_scales.iter().flatten())
        .chain(gg.sh.iter().flatten())
        .chain(&gg.opacity_logits)
        .chain(&gg.mask_logits)
        .chain(&gg.log_reflections);
    assert!(flat.into_iter().all(|v| v.is_finite()), "a Gaussian gradient is not finite");
    for p in &gr.planes {
        assert!(
            p.centre.is_finite() && p.normal.is_finite() && p.r0_logit.is_finite(),
            "plane gradient not finite"
        );
    }
    f
}

fn scene() -> Scene {
    random_scene(&SceneSpec { seed: 41, gaussians: 40, planes: 2, ..Default::default() })
}

fn look_from(scene: &mut Scene, eye: DVec3, target: DVec3) {
    scene.camera.pose = Pose::look_at(eye, target, DVec3::Y);
}

#[test]
fn grazing_view_gives_strength_near_one() {
    let mut s = scene();
    s.planes.truncate(1);
    let p = s.planes[0];
    // 89.5 degrees from the normal: the rays meet the plane almost tangentially.
    let dir = (p.axis * 89.5f64.to_radians().sin() + p.unit_normal() * 89.5f64.to_radians().cos())
        .normalize();
    look_from(&mut s, p.centre + 3.0 * dir, p.centre);
    let f = render_finite(&s);
    let max = f.strength_raw.data.iter().copied().fold(0.0, f64::max);
    assert!(f.hit.data.contains(&1), "the plane must be hit");
    assert!(max > 0.9, "Schlick at grazing incidence tends to 1, got {max}");
}

#[test]
fn camera_on_the_plane_and_behind_it_skip_the_reflection() {
    for offset in [0.0, -1.5] {
        let mut s = scene();
        s.planes.truncate(1);
        let p = s.planes[0];
        // Exactly on the plane (signed distance 0), then behind it.
        let eye = p.centre + 0.3 * p.axis + offset * p.unit_normal();
        look_from(&mut s, eye, eye + p.bitangent() * 0.2 - p.unit_normal() + 0.1 * p.axis);
        if offset == 0.0 {
            // The pose's centre is recomputed from R and t; put the plane exactly through it.
            s.planes[0].centre = s.camera.pose.centre();
            assert_eq!(s.planes[0].signed_distance(s.camera.pose.centre()), 0.0);
        }
        let f = render_finite(&s);
        assert!(f.planes[0].is_none(), "no mirrored pass when the camera is not in front");
        assert!(f.hit.data.iter().all(|&h| h == 0));
        assert_eq!(f.color, f.transmission);
    }
}

#[test]
fn plane_seen_edge_on() {
    let mut s = scene();
    s.planes.truncate(1);
    let p = s.planes[0];
    // The camera 1e-9 in front of the plane's support, looking along the plane.
    let eye = p.centre - 3.0 * p.axis + 1e-9 * p.unit_normal();
    look_from(&mut s, eye, p.centre + 1e-9 * p.unit_normal());
    let f = render_finite(&s);
    let hits = f.hit.data.iter().filter(|&&h| h == 1).count();
    assert!(
        hits <= (f.width() as usize),
        "an edge-on plane covers at most a line, got {hits} pixels"
    );
}

#[test]
fn zero_area_plane_is_an_error() {
    for (w, h) in [(0.0, 1.0), (1.0, 0.0), (-1.0, 1.0)] {
        let mut s = scene();
        s.planes[1].width = w;
        s.planes[1].height = h;
        let err = render(&s.gaussians, &s.planes, &s.camera, &RenderSettings::default())
            .expect_err("must fail");
        let msg = err.to_string();
        assert!(msg.contains("plane 1") && msg.contains("zero-area"), "{msg}");
    }
    let mut s = scene();
    s.planes[0].normal = DVec3::ZERO;
    let err = render(&s.gaussians, &s.planes, &s.camera, &RenderSettings::default())
        .expect_err("must fail");
    assert!(err.to_string().contains("plane 0: normal has zero length"), "{err}");
}

#[test]
fn tiny_and_huge_scales() {
    for log_scale in [1e-8f64.ln(), 1e3f64.ln()] {
        let mut s = scene();
        for v in s.gaussians.log_scales.iter_mut().step_by(2) {
            *v = [log_scale; 3];
        }
        let f = render_finite(&s);
        assert!(f.alpha.data.iter().any(|&a| a > 0.0));
    }
    // Extremely flat (a disc) and extremely elongated (a needle).
    let mut s = scene();
    for (i, v) in s.gaussians.log_scales.iter_mut().enumerate() {
        *v = if i % 2 == 0 { [0.0, 0.0, 1e-8f64.ln()] } else { [1e-8f64.ln(), 1e-8f64.ln(), 1.0] };
    }
    render_finite(&s);
}

#[test]
fn gaussians_behind_the_camera_and_straddling_the_near_plane() {
    let mut s = scene();
    s.planes.clear();
    let pose = s.camera.pose;
    let world = |c: DVec3| pose.rotation.transpose() * (c - pose.translation);
    let n = s.gaussians.len();
    for i in 0..n {
        let z = match i % 4 {
            0 => -2.0, // behind the camera
            1 => 0.21, // just past the near plane, large: reaches behind the camera
            2 => 0.19, // just short of it: culled
            _ => continue,
        };
        s.gaussians.means[i] = world(DVec3::new(0.05 * (i as f64 - 20.0), 0.0, z)).to_array();
        if i % 4 == 1 {
            s.gaussians.log_scales[i] = [0.5f64.ln(); 3];
        }
    }
    let f = render_finite(&s);
    let vis = &f.depth;
    assert!(
        vis.data.iter().all(|&d| d == 0.0 || d >= 0.2 - 1e-12),
        "no blended depth below the near plane"
    );
}

#[test]
fn empty_scene_and_background() {
    let mut s = scene();
    s.gaussians = trgs_core::Gaussians::empty(3);
    let f = render_finite(&s);
    assert!(f.transmission.data.iter().all(|&v| v == 0.0));
    assert!(f.alpha.data.iter().all(|&v| v == 0.0));
    let settings = RenderSettings { background: [0.25, 0.5, 1.0], ..Default::default() };
    let f = render(&s.gaussians, &s.planes, &s.camera, &settings).expect("valid");
    assert_eq!(&f.transmission.data[..3], &[0.25, 0.5, 1.0]);
}

#[test]
fn one_pixel_image() {
    let mut s = scene();
    let k = s.camera.intrinsics;
    s.camera.intrinsics =
        Intrinsics { width: 1, height: 1, cx: 0.5, cy: 0.5, fx: k.fx / 32.0, fy: k.fy / 32.0 };
    let f = render_finite(&s);
    assert_eq!((f.width(), f.height()), (1, 1));
}

#[test]
fn non_finite_inputs_are_rejected_with_attribute_and_index() {
    let base = scene();
    let settings = RenderSettings::default();
    let bad = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY];
    type Poke = fn(&mut Scene, f64);
    let cases: [(&str, Poke); 7] = [
        ("Gaussian 7: mean", |s, v| s.gaussians.means[7][1] = v),
        ("Gaussian 7: rotation", |s, v| s.gaussians.rotations[7][0] = v),
        ("Gaussian 7: log_scale", |s, v| s.gaussians.log_scales[7][2] = v),
        ("Gaussian 7: opacity_logit", |s, v| s.gaussians.opacity_logits[7] = v),
        ("Gaussian 7: sh", |s, v| s.gaussians.sh[7 * 16 + 5][2] = v),
        ("Gaussian 7: mask_logit", |s, v| s.gaussians.mask_logits[7] = v),
        ("Gaussian 7: log_reflection", |s, v| s.gaussians.log_reflections[7] = v),
    ];
    for v in bad {
        for (expect, poke) in cases {
            let mut s = base.clone();
            poke(&mut s, v);
            let err = render(&s.gaussians, &s.planes, &s.camera, &settings).expect_err("must fail");
            assert!(err.to_string().starts_with(expect), "expected '{expect}', got '{err}'");
            assert!(matches!(err, InvalidInput::NonFinite { index: 7, .. }));
        }
        let mut s = base.clone();
        s.planes[1].centre.x = v;
        let err = render(&s.gaussians, &s.planes, &s.camera, &settings).expect_err("must fail");
        assert!(err.to_string().contains("plane 1: centre is not finite"), "{err}");
        let mut s = base.clone();
        s.planes[0].r0_logit = v;
        assert!(render(&s.gaussians, &s.planes, &s.camera, &settings).is_err());
        let mut s = base.clone();
        s.camera.pose.translation.z = v;
        let err = render(&s.gaussians, &s.planes, &s.camera, &settings).expect_err("must fail");
        assert!(err.to_string().contains("camera pose"), "{err}");
        let mut s = base.clone();
        s.camera.intrinsics.fx = v;
        assert!(render(&s.gaussians, &s.planes, &s.camera, &settings).is_err());
    }
    // A zero quaternion has no rotation.
    let mut s = base.clone();
    s.gaussians.rotations[3] = [0.0; 4];
    let err = render(&s.gaussians, &s.planes, &s.camera, &settings).expect_err("must fail");
    assert!(err.to_string().contains("Gaussian 3: rotation"), "{err}");
    // Mismatched attribute lengths.
    let mut s = base.clone();
    s.gaussians.opacity_logits.pop();
    let err = render(&s.gaussians, &s.planes, &s.camera, &settings).expect_err("must fail");
    assert!(err.to_string().contains("opacity_logits"), "{err}");
    // A zero-size image.
    let mut s = base;
    s.camera = Camera::new("empty", Intrinsics { width: 0, ..s.camera.intrinsics }, s.camera.pose);
    assert!(render(&s.gaussians, &s.planes, &s.camera, &settings).is_err());
}

#[test]
fn stage_two_block_keeps_plane_gradients_and_stops_reflection_into_gaussians() {
    let s = random_scene(&SceneSpec { seed: 43, gaussians: 30, planes: 1, ..Default::default() });
    let settings = RenderSettings::default();
    let f = render(&s.gaussians, &s.planes, &s.camera, &settings).expect("valid");
    let mut g = FrameGrads::zeros_like(&f);
    g.color.data.iter_mut().for_each(|v| *v = 1.0);
    let full = backward(
        &s.gaussians,
        &s.planes,
        &s.camera,
        &settings,
        &f,
        &g,
        &BackwardOptions::default(),
    )
    .expect("valid");
    let opts = BackwardOptions { block_reflection_to_gaussians: true };
    let blocked =
        backward(&s.gaussians, &s.planes, &s.camera, &settings, &f, &g, &opts).expect("valid");
    assert_eq!(full.planes, blocked.planes, "planes learn in stage 2");
    assert!(
        blocked.gaussians.log_reflections.iter().all(|&v| v == 0.0),
        "a only receives gradient from C_r"
    );
    assert!(full.gaussians.log_reflections.iter().any(|&v| v != 0.0));
    // The blocked Gaussian gradient is the one of a loss on pass 1 alone with C_r held fixed.
    assert_ne!(full.gaussians.means, blocked.gaussians.means);
}

#[test]
fn bad_plane_values_settings_and_reflection_intensities_are_named() {
    let base = scene();
    let settings = RenderSettings::default();
    let fails = |s: &Scene, settings: &RenderSettings| {
        render(&s.gaussians, &s.planes, &s.camera, settings).expect_err("must fail").to_string()
    };
    // Every plane parameter, not only the centre.
    type Poke = fn(&mut Scene);
    let cases: [(&str, Poke); 5] = [
        ("plane 1: normal is not finite", |s| s.planes[1].normal.y = f64::NAN),
        ("plane 1: axis is not finite", |s| s.planes[1].axis.z = f64::INFINITY),
        ("plane 1: width is not finite", |s| s.planes[1].width = f64::NAN),
        ("plane 1: height is not finite", |s| s.planes[1].height = f64::NEG_INFINITY),
        ("plane 1: normal length", |s| s.planes[1].normal *= 1e200),
    ];
    for (expect, poke) in cases {
        let mut s = base.clone();
        poke(&mut s);
        let err = fails(&s, &settings);
        assert!(err.contains(expect), "expected '{expect}', got '{err}'");
    }
    // Settings the GPU renderer refuses too.
    for (bad, expect) in [
        (RenderSettings { near: 0.0, ..settings }, "near"),
        (RenderSettings { near: f64::NAN, ..settings }, "near"),
        (RenderSettings { background: [0.0, f64::INFINITY, 0.0], ..settings }, "background"),
    ] {
        let err = fails(&base, &bad);
        assert!(err.contains(expect), "expected '{expect}', got '{err}'");
    }
    // A reflection intensity f32 could not carry through compose.
    let mut s = base.clone();
    s.gaussians.log_reflections[4] = 31.0;
    let err = fails(&s, &settings);
    assert!(err.contains("Gaussian 4: log_reflection 31 is out of range"), "{err}");
}
