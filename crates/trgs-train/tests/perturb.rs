//! Stage `perturb` (the opacity perturbation on the GPU) against its twin: the selection of
//! `seen_through_planes` and the noise of `perturb_opacities`. Two planes, cameras on both
//! sides, glass Gaussians; Gaussians within a millimetre of a selection boundary (the margin
//! behind a plane, a rectangle's edge seen from a camera) are moved off it first, since f32 and
//! f64 may decide those differently. The selection and the count agree exactly, the new opacities
//! within f32 rounding, and every other Gaussian keeps its bits.
use glam::DVec3;
use trgs_core::fixtures::{SceneSpec, random_scene};
use trgs_core::rng::Rng;
use trgs_core::scene::{Gaussians, Material, Population, ReflectionPlane};
use trgs_render::{GpuContext, GpuScene};
use trgs_train::stages::perturb::{
    BEHIND_MARGIN, GpuPerturb, PERTURB_AMPLITUDE, perturb_opacities, seen_through_planes,
};

/// How close (in metres) the centre `mu` comes to deciding otherwise for any plane and camera.
fn closeness(mu: DVec3, planes: &[ReflectionPlane], cameras: &[DVec3]) -> f64 {
    let mut close = f64::INFINITY;
    for p in planes {
        let n = p.unit_normal();
        let behind = (mu - p.centre).dot(n) + BEHIND_MARGIN * p.width.min(p.height);
        close = close.min(behind.abs());
        if behind >= 0.0 {
            continue;
        }
        for &c in cameras {
            let side = (c - p.centre).dot(n);
            close = close.min(side.abs());
            if side <= 0.0 {
                continue;
            }
            let d = mu - c;
            let hit = c + d * (-side / d.dot(n)) - p.centre;
            close = close.min((hit.dot(p.axis).abs() - 0.5 * p.width).abs());
            close = close.min((hit.dot(p.bitangent()).abs() - 0.5 * p.height).abs());
        }
    }
    close
}

#[test]
fn the_gpu_perturbs_as_the_twin_does() {
    let ctx = GpuContext::new().expect("adapter");
    let planes = [
        ReflectionPlane::new(DVec3::ZERO, DVec3::Z, DVec3::X, 2.0, 1.0, Material::Glass),
        ReflectionPlane::new(
            DVec3::new(2.5, 0.0, 0.0),
            DVec3::X,
            DVec3::Y,
            1.5,
            1.2,
            Material::Mirror,
        ),
    ];
    let mut rng = Rng::new(4);
    let point = |rng: &mut Rng| {
        DVec3::new(rng.range(-3.0, 4.0), rng.range(-1.5, 1.5), rng.range(-4.0, 3.0))
    };
    let cameras: Vec<DVec3> = (0..24).map(|_| point(&mut rng)).collect();
    let spec =
        SceneSpec { gaussians: 6000, sh_degree: 0, glass_fraction: 0.1, ..SceneSpec::default() };
    let mut g: Gaussians<f32> = random_scene(&spec).gaussians.cast();
    for i in 0..g.len() {
        let mut mu = point(&mut rng);
        while closeness(mu, &planes, &cameras) < 1e-3 {
            mu = point(&mut rng);
        }
        g.means[i] = mu.to_array().map(|v| v as f32);
        g.opacity_logits[i] = rng.range(-6.0, 6.0) as f32;
    }
    // The means as f32 are what both sides see.
    let scene = GpuScene::upload(&ctx, &g, &planes).expect("upload");
    let seed = 0x5eed;
    let perturb = GpuPerturb::new(&ctx);
    let read_before = ctx.bytes_read();
    let count =
        perturb.run(&ctx, &scene, &cameras, PERTURB_AMPLITUDE, seed).expect("perturb on the GPU");
    assert_eq!(ctx.bytes_read() - read_before, 4, "only the count comes back");
    let got = scene.read(&ctx).expect("readback");
    let selected = seen_through_planes(&g, &planes, &cameras);
    let mut twin = g.clone();
    let twin_count = perturb_opacities(&mut twin, &selected, PERTURB_AMPLITUDE, seed);
    assert_eq!(count, twin_count, "perturbed Gaussians");
    assert!(count > 300 && count < g.len() / 2, "{count} of {} perturbed", g.len());
    let sigmoid = |l: f32| 1.0 / (1.0 + (-f64::from(l)).exp());
    for i in 0..g.len() {
        let (a, b) = (got.opacity_logits[i], twin.opacity_logits[i]);
        if !selected[i] {
            assert_eq!(a.to_bits(), g.opacity_logits[i].to_bits(), "Gaussian {i} was not selected");
            continue;
        }
        assert_eq!(g.populations[i], Population::Primary, "a glass Gaussian was selected");
        assert!((sigmoid(a) - sigmoid(b)).abs() < 2e-6, "Gaussian {i}: {a} against {b}");
    }
    // A scene without cameras perturbs nothing.
    let none = perturb.run(&ctx, &scene, &[], PERTURB_AMPLITUDE, seed);
    assert_eq!(none.expect("no cameras"), 0);
}
