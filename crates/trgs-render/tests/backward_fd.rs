//! The GPU backward against central finite differences of the GPU forward, in f32.
//!
//! Loss: a random linear functional of every layer the GPU renders (C, C_t, D_t, V, M, alpha,
//! R_raw, R, C_r and each plane's C_raw and A), summed in f64 after readback. Parameters: every
//! attribute of a sample of Gaussians (mean, quaternion, log-scale, opacity, the first SH
//! coefficients, mask, reflection intensity) and every plane's centre, normal and R0.
//!
//! Documented tolerance (f32): step h = 1e-3 (the forward's rounding noise in the loss is, by
//! estimate, about 1e-5, so the quotient carries about 1e-2 of noise); a parameter passes when
//! |analytic - fd| <= 3e-2 max(|fd|, |analytic|) + 1e-2 rms(kind), with rms(kind) the RMS of the
//! analytic gradients of its attribute kind. A step that changes a discrete decision of the
//! renderer (the CPU twin's fingerprint of the perturbed scenes: culling, order, stop points,
//! alpha thresholds, hit mask) measures a jump, not a derivative, and is skipped and counted.
use trgs_core::fixtures::{Scene, random_scene};
use trgs_core::pipeline::RenderSettings;
use trgs_core::reference::{self, FrameGrads};
use trgs_core::rng::Rng;
use trgs_core::scene::Gaussians;
use trgs_render::{
    BackwardOptions, DeviceOptions, GpuContext, GpuScene, LayerGrads, RenderOptions, Renderer,
};

mod common;

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
    fn kind(self) -> &'static str {
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

    fn slot(self, s: &mut Scene) -> &mut f64 {
        let g = &mut s.gaussians;
        match self {
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

    fn analytic(self, g: &Gaussians<f32>, planes: &[trgs_core::plane_grad::PlaneGrad]) -> f64 {
        match self {
            Param::Mean(i, a) => f64::from(g.means[i][a]),
            Param::Rotation(i, a) => f64::from(g.rotations[i][a]),
            Param::LogScale(i, a) => f64::from(g.log_scales[i][a]),
            Param::Opacity(i) => f64::from(g.opacity_logits[i]),
            Param::Sh(j, c) => f64::from(g.sh[j][c]),
            Param::Mask(i) => f64::from(g.mask_logits[i]),
            Param::Reflection(i) => f64::from(g.log_reflections[i]),
            Param::PlaneCentre(k, a) => planes[k].centre[a],
            Param::PlaneNormal(k, a) => planes[k].normal[a],
            Param::PlaneR0(k) => planes[k].r0_logit,
        }
    }
}

fn weights(frame: &reference::Frame, seed: u64) -> FrameGrads {
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

fn dot(a: &trgs_core::Image<f32>, b: &trgs_core::Image<f64>) -> f64 {
    a.data.iter().zip(&b.data).map(|(&x, y)| f64::from(x) * y).sum()
}

struct Gpu {
    ctx: GpuContext,
    renderer: Renderer,
    options: RenderOptions,
}

impl Gpu {
    fn loss(&self, s: &Scene, w: &FrameGrads) -> f64 {
        let scene =
            GpuScene::upload(&self.ctx, &s.gaussians.cast::<f32>(), &s.planes).expect("valid");
        let frame = self.renderer.render(&scene, &s.camera, &self.options).expect("render");
        let im = frame.read_images(&self.ctx).expect("readback");
        let mut l = dot(&im.color, &w.color)
            + dot(&im.transmission, &w.transmission)
            + dot(&im.depth, &w.depth)
            + dot(&im.depth_variance, &w.depth_variance)
            + dot(&im.mask, &w.mask)
            + dot(&im.alpha, &w.alpha)
            + dot(&im.strength_raw, &w.strength_raw)
            + dot(&im.strength, &w.strength)
            + dot(&im.reflection, &w.reflection);
        for (p, wp) in im.planes.iter().zip(&w.planes) {
            if let Some(p) = p {
                l += dot(&p.raw_color, &wp.raw_color) + dot(&p.intensity, &wp.intensity);
            }
        }
        l
    }
}

fn check(seed: u64, planes: usize, angle: f64) {
    let mut spec = common::spec(seed, 40, planes, angle);
    (spec.width, spec.height, spec.sh_degree) = (48, 36, 1);
    // The scene in f32 precision, so that the twin's fingerprint sees what the GPU renders.
    let mut scene = random_scene(&spec);
    scene.gaussians = scene.gaussians.cast::<f32>().cast::<f64>();
    let ctx = GpuContext::with_options(&DeviceOptions::default()).expect("adapter");
    let gpu = Gpu {
        renderer: Renderer::new(&ctx),
        ctx,
        options: RenderOptions { depth_variance: true, ..Default::default() },
    };
    let settings = RenderSettings::default();
    let twin = |s: &Scene| {
        reference::render(&s.gaussians, &s.planes, &s.camera, &settings).expect("valid scene")
    };
    let base = twin(&scene);
    let w = weights(&base, seed ^ 0xfd);

    let g32 = scene.gaussians.cast::<f32>();
    let gpu_scene = GpuScene::upload(&gpu.ctx, &g32, &scene.planes).expect("valid");
    let mut frame = gpu.renderer.render(&gpu_scene, &scene.camera, &gpu.options).expect("render");
    let grads = LayerGrads::upload(&gpu.ctx, &frame, &w).expect("finite");
    let out = gpu
        .renderer
        .backward(&gpu_scene, &mut frame, &grads, &BackwardOptions::default())
        .expect("backward");
    let gg = out.gaussians.read(&gpu.ctx).expect("readback");
    let plane_grads = out.planes.read(&gpu.ctx).expect("plane readback");

    let mut params = Vec::new();
    let coeffs = scene.gaussians.sh_coeffs();
    for i in (0..scene.gaussians.len()).step_by(4) {
        for a in 0..3 {
            params.extend([Param::Mean(i, a), Param::LogScale(i, a), Param::Sh(i * coeffs, a)]);
        }
        params.extend((0..4).map(|a| Param::Rotation(i, a)));
        params.extend([Param::Opacity(i), Param::Reflection(i), Param::Sh(i * coeffs + 1, 0)]);
        if scene.gaussians.populations[i] == trgs_core::scene::Population::Glass {
            params.push(Param::Mask(i));
        }
    }
    for k in 0..scene.planes.len() {
        for a in 0..3 {
            params.extend([Param::PlaneCentre(k, a), Param::PlaneNormal(k, a)]);
        }
        params.push(Param::PlaneR0(k));
    }
    let mut rms = std::collections::HashMap::<&str, (f64, usize)>::new();
    for &p in &params {
        let e = rms.entry(p.kind()).or_default();
        e.0 += p.analytic(&gg, &plane_grads).powi(2);
        e.1 += 1;
    }
    let h = 1e-3;
    let base_fp = base.fingerprint();
    let (mut checked, mut skipped, mut failed, mut worst) = (0, 0, 0, (0.0f64, String::new()));
    for &p in &params {
        let mut plus = scene.clone();
        *p.slot(&mut plus) += h;
        let mut minus = scene.clone();
        *p.slot(&mut minus) -= h;
        if let Param::PlaneNormal(k, _) = p {
            plus.planes[k].orthogonalise_axis();
            minus.planes[k].orthogonalise_axis();
        }
        let f32_scene = |s: &mut Scene| s.gaussians = s.gaussians.cast::<f32>().cast::<f64>();
        f32_scene(&mut plus);
        f32_scene(&mut minus);
        if twin(&plus).fingerprint() != base_fp || twin(&minus).fingerprint() != base_fp {
            skipped += 1;
            continue;
        }
        let fd = (gpu.loss(&plus, &w) - gpu.loss(&minus, &w)) / (2.0 * h);
        let a = p.analytic(&gg, &plane_grads);
        let (ss, n) = rms[p.kind()];
        let floor = 1e-2 * (ss / n as f64).sqrt();
        let err = (a - fd).abs() / (fd.abs().max(a.abs()) + floor / 3e-2).max(1e-30);
        checked += 1;
        if (a - fd).abs() > 3e-2 * fd.abs().max(a.abs()) + floor {
            failed += 1;
            eprintln!("{p:?}: analytic {a:.6e}, finite difference {fd:.6e}");
        }
        if err > worst.0 {
            worst = (err, format!("{p:?}: analytic {a:.6e}, fd {fd:.6e}"));
        }
    }
    eprintln!(
        "seed {seed}, {planes} planes: {checked} parameters checked, {skipped} skipped at a discontinuity, {failed} outside tolerance; worst {:.2e} ({})",
        worst.0, worst.1
    );
    assert!(checked >= params.len() * 3 / 4, "too many parameters at a discontinuity");
    assert_eq!(failed, 0, "GPU gradients disagree with finite differences");
}

#[test]
fn gpu_gradients_match_finite_differences_without_planes() {
    check(71, 0, 20.0);
}

#[test]
fn gpu_gradients_match_finite_differences_with_a_plane() {
    check(72, 1, 30.0);
}

#[test]
fn gpu_gradients_match_finite_differences_with_two_planes() {
    check(73, 2, 35.0);
}
