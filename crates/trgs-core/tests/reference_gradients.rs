//! The CPU reference's analytic backward against central finite differences in f64, for every
//! differentiable input: Gaussian mean, quaternion, log-scale, opacity, each SH coefficient, mask,
//! reflection intensity, and each plane's centre, normal and R0.
//!
//! The loss is a random linear functional of every output layer, so every layer's backward path
//! is exercised. The error of each parameter is `|analytic - fd| / max(|fd|, |analytic|, floor)`
//! with `floor = 1e-3 x` the RMS finite-difference gradient of that attribute in the scene (scale
//! aware: a gradient a thousand times below its attribute's typical size is compared in absolute
//! terms). A finite difference whose two evaluations change a discrete decision of the renderer
//! (the fingerprint: culling, order, stop points, thresholds, hit mask) measures a step, not a
//! derivative; it is retried with a 10x smaller step and otherwise counted and reported.
use trgs_core::fixtures::{Scene, SceneSpec, random_scene};
use trgs_core::pipeline::{ReflectionModel, RenderSettings};
use trgs_core::reference::{BackwardOptions, Frame, FrameGrads, backward, render};
use trgs_core::rng::Rng;

#[derive(Clone, Copy, Debug)]
enum Param {
    Mean(usize, usize),
    Rotation(usize, usize),
    LogScale(usize, usize),
    Opacity(usize),
    Sh(usize, usize),
    Mask(usize),
    Reflection(usize),
    PlaneCentre(usize, usize),
    PlaneNormal(usize, usize),
    PlaneR0(usize),
}

impl Param {
    fn kind(&self) -> &'static str {
        match self {
            Param::Mean(..) => "mean",
            Param::Rotation(..) => "rotation",
            Param::LogScale(..) => "log_scale",
            Param::Opacity(..) => "opacity",
            Param::Sh(..) => "sh",
            Param::Mask(..) => "mask",
            Param::Reflection(..) => "reflection",
            Param::PlaneCentre(..) => "plane_centre",
            Param::PlaneNormal(..) => "plane_normal",
            Param::PlaneR0(..) => "plane_r0",
        }
    }

    fn slot<'a>(&self, s: &'a mut Scene) -> &'a mut f64 {
        let g = &mut s.gaussians;
        match *self {
            Param::Mean(i, a) => &mut g.means[i][a],
            Param::Rotation(i, a) => &mut g.rotations[i][a],
            Param::LogScale(i, a) => &mut g.log_scales[i][a],
            Param::Opacity(i) => &mut g.opacity_logits[i],
            Param::Sh(j, c) => &mut g.sh[j][c],
            Param::Mask(i) => &mut g.mask_logits[i],
            Param::Reflection(i) => &mut g.log_reflections[i],
            Param::PlaneCentre(k, a) => &mut s.planes[k].centre[a],
            Param::PlaneNormal(k, a) => &mut s.planes[k].normal[a],
            Param::PlaneR0(k) => &mut s.planes[k].r0_logit,
        }
    }

    fn analytic(&self, gr: &trgs_core::reference::SceneGrads) -> f64 {
        let g = &gr.gaussians;
        match *self {
            Param::Mean(i, a) => g.means[i][a],
            Param::Rotation(i, a) => g.rotations[i][a],
            Param::LogScale(i, a) => g.log_scales[i][a],
            Param::Opacity(i) => g.opacity_logits[i],
            Param::Sh(j, c) => g.sh[j][c],
            Param::Mask(i) => g.mask_logits[i],
            Param::Reflection(i) => g.log_reflections[i],
            Param::PlaneCentre(k, a) => gr.planes[k].centre[a],
            Param::PlaneNormal(k, a) => gr.planes[k].normal[a],
            Param::PlaneR0(k) => gr.planes[k].r0_logit,
        }
    }
}

fn all_params(s: &Scene) -> Vec<Param> {
    let g = &s.gaussians;
    let mut v = Vec::new();
    for i in 0..g.len() {
        for a in 0..3 {
            v.push(Param::Mean(i, a));
            v.push(Param::LogScale(i, a));
        }
        for a in 0..4 {
            v.push(Param::Rotation(i, a));
        }
        v.push(Param::Opacity(i));
        v.push(Param::Mask(i));
        v.push(Param::Reflection(i));
    }
    for j in 0..g.sh.len() {
        for c in 0..3 {
            v.push(Param::Sh(j, c));
        }
    }
    for k in 0..s.planes.len() {
        for a in 0..3 {
            v.push(Param::PlaneCentre(k, a));
            v.push(Param::PlaneNormal(k, a));
        }
        v.push(Param::PlaneR0(k));
    }
    v
}

/// Random weights for every layer: the loss is their inner product with the frame.
fn random_weights(frame: &Frame, seed: u64) -> FrameGrads {
    let mut rng = Rng::new(seed);
    let mut g = FrameGrads::zeros_like(frame);
    let mut fill = |img: &mut trgs_core::Image<f64>, scale: f64| {
        for v in &mut img.data {
            *v = scale * rng.range(-1.0, 1.0);
        }
    };
    fill(&mut g.color, 1.0);
    fill(&mut g.transmission, 1.0);
    fill(&mut g.depth, 0.2);
    fill(&mut g.depth_variance, 0.5);
    fill(&mut g.mask, 1.0);
    fill(&mut g.alpha, 1.0);
    fill(&mut g.strength_raw, 1.0);
    fill(&mut g.strength, 1.0);
    fill(&mut g.reflection, 1.0);
    for p in &mut g.planes {
        fill(&mut p.raw_color, 1.0);
        fill(&mut p.intensity, 1.0);
    }
    g
}

fn loss(frame: &Frame, w: &FrameGrads) -> f64 {
    let dot = |a: &trgs_core::Image<f64>, b: &trgs_core::Image<f64>| -> f64 {
        a.data.iter().zip(&b.data).map(|(x, y)| x * y).sum()
    };
    let mut l = dot(&frame.color, &w.color)
        + dot(&frame.transmission, &w.transmission)
        + dot(&frame.depth, &w.depth)
        + dot(&frame.depth_variance, &w.depth_variance)
        + dot(&frame.mask, &w.mask)
        + dot(&frame.alpha, &w.alpha)
        + dot(&frame.strength_raw, &w.strength_raw)
        + dot(&frame.strength, &w.strength)
        + dot(&frame.reflection, &w.reflection);
    for (p, wp) in frame.planes.iter().zip(&w.planes) {
        if let Some(p) = p {
            l += dot(&p.raw_color, &wp.raw_color) + dot(&p.intensity, &wp.intensity);
        }
    }
    l
}

struct Report {
    worst: f64,
    worst_param: String,
    checked: usize,
    skipped: usize,
    /// Per attribute kind: (worst relative error, largest |gradient|).
    per_kind: std::collections::BTreeMap<&'static str, (f64, f64)>,
}

fn check_scene(spec: &SceneSpec, options: BackwardOptions, settings: RenderSettings) -> Report {
    check_prepared(random_scene(spec), spec.seed, options, settings)
}

fn check_prepared(
    scene: Scene,
    seed: u64,
    options: BackwardOptions,
    settings: RenderSettings,
) -> Report {
    let render_of =
        |s: &Scene| render(&s.gaussians, &s.planes, &s.camera, &settings).expect("valid scene");
    let frame = render_of(&scene);
    let weights = random_weights(&frame, seed ^ 0xABCD);
    let grads = backward(
        &scene.gaussians,
        &scene.planes,
        &scene.camera,
        &settings,
        &frame,
        &weights,
        &options,
    )
    .expect("valid scene");
    let base_fp = frame.fingerprint();

    let params = all_params(&scene);
    let mut fd = vec![f64::NAN; params.len()];
    let mut skipped = 0;
    for (n, p) in params.iter().enumerate() {
        let mut found = None;
        for eps in [1e-6, 1e-7] {
            let mut plus = scene.clone();
            *p.slot(&mut plus) += eps;
            let mut minus = scene.clone();
            *p.slot(&mut minus) -= eps;
            if let Param::PlaneNormal(k, _) = p {
                // The in-plane axis follows the normal, as training re-orthogonalises it.
                plus.planes[*k].orthogonalise_axis();
                minus.planes[*k].orthogonalise_axis();
            }
            let (fp, fm) = (render_of(&plus), render_of(&minus));
            if fp.fingerprint() == base_fp && fm.fingerprint() == base_fp {
                found = Some((loss(&fp, &weights) - loss(&fm, &weights)) / (2.0 * eps));
                break;
            }
        }
        match found {
            Some(v) => fd[n] = v,
            None => skipped += 1,
        }
    }
    // Scale of each attribute kind: RMS of its finite-difference gradients.
    let mut scale = std::collections::HashMap::<&str, (f64, usize)>::new();
    for (p, v) in params.iter().zip(&fd) {
        if v.is_finite() {
            let e = scale.entry(p.kind()).or_default();
            e.0 += v * v;
            e.1 += 1;
        }
    }
    let mut report = Report {
        worst: 0.0,
        worst_param: String::new(),
        checked: 0,
        skipped,
        per_kind: Default::default(),
    };
    for (p, &f) in params.iter().zip(&fd) {
        if !f.is_finite() {
            continue;
        }
        let (ss, cnt) = scale[p.kind()];
        let floor = 1e-3 * (ss / cnt as f64).sqrt() + 1e-12;
        let a = p.analytic(&grads);
        let err = (a - f).abs() / f.abs().max(a.abs()).max(floor);
        report.checked += 1;
        let kind = report.per_kind.entry(p.kind()).or_default();
        kind.0 = kind.0.max(err);
        kind.1 = kind.1.max(f.abs());
        if err > report.worst {
            report.worst = err;
            report.worst_param = format!("{p:?}: analytic {a:.9e}, finite difference {f:.9e}");
        }
    }
    report
}

fn assert_gradients(spec: SceneSpec, options: BackwardOptions) {
    assert_gradients_with(spec, options, RenderSettings::default());
}

fn assert_gradients_with(spec: SceneSpec, options: BackwardOptions, settings: RenderSettings) {
    let r = check_scene(&spec, options, settings);
    assert_report(&spec, spec.planes, r);
}

fn assert_report(label: &dyn std::fmt::Debug, planes: usize, r: Report) {
    let spec = label;
    println!(
        "{spec:?}: {} parameters checked, {} skipped at a discontinuity, worst relative error {:.2e} ({})",
        r.checked, r.skipped, r.worst, r.worst_param
    );
    for (kind, (err, size)) in &r.per_kind {
        println!("  {kind:>13}: worst relative error {err:.2e}, largest |gradient| {size:.3e}");
    }
    assert!(r.worst <= 1e-4, "worst relative error {:.3e} at {}", r.worst, r.worst_param);
    // The plane parameters must really be exercised, not compared as zero against zero.
    if planes > 0 {
        for kind in ["plane_centre", "plane_normal", "plane_r0", "mask", "reflection"] {
            assert!(r.per_kind[kind].1 > 1e-3, "{kind} gradients are all (near) zero");
        }
    }
    assert!(
        r.skipped * 100 <= r.checked + r.skipped,
        "too many discontinuous parameters: {}",
        r.skipped
    );
}

#[test]
fn gradients_no_plane() {
    assert_gradients(
        SceneSpec { seed: 11, gaussians: 20, planes: 0, ..Default::default() },
        BackwardOptions::default(),
    );
}

#[test]
fn gradients_one_plane() {
    assert_gradients(
        SceneSpec { seed: 12, gaussians: 24, planes: 1, ..Default::default() },
        BackwardOptions::default(),
    );
}

#[test]
fn gradients_two_planes() {
    assert_gradients(
        SceneSpec { seed: 13, gaussians: 24, planes: 2, ..Default::default() },
        BackwardOptions::default(),
    );
}

#[test]
fn gradients_grazing_view_80_degrees() {
    assert_gradients(
        SceneSpec {
            seed: 14,
            gaussians: 24,
            planes: 1,
            view_angle_deg: 80.0,
            ..Default::default()
        },
        BackwardOptions::default(),
    );
}

#[test]
fn gradients_without_fresnel_or_intensity() {
    for (fresnel, intensity) in [(false, true), (true, false), (false, false)] {
        let settings = RenderSettings {
            reflection: ReflectionModel { fresnel, intensity },
            ..Default::default()
        };
        assert_gradients_with(
            SceneSpec { seed: 15, gaussians: 24, planes: 1, ..Default::default() },
            BackwardOptions::default(),
            settings,
        );
    }
}

#[test]
fn gradients_with_plane_normals_of_other_lengths() {
    // Training steps the raw normal, so its length drifts from 1: the gradient must hold for
    // any length (the normalisation's Jacobian), not only at 1.
    for length in [2.5, 0.1] {
        let spec = SceneSpec { seed: 16, gaussians: 24, planes: 2, ..Default::default() };
        let mut scene = random_scene(&spec);
        for p in &mut scene.planes {
            p.normal *= length;
        }
        let r = check_prepared(scene, spec.seed, BackwardOptions::default(), Default::default());
        assert_report(&format!("normals of length {length}"), spec.planes, r);
    }
}
