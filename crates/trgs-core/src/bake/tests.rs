use super::*;
use crate::metrics::psnr;
use crate::pipeline::RenderSettings;
use crate::reference::render;
use crate::scene::{Intrinsics, Material, Pose};

fn camera(name: &str, eye: DVec3) -> Camera {
    Camera::new(
        name,
        Intrinsics::from_fov_x(0.9, 48, 36),
        Pose::look_at(eye, DVec3::new(0.0, 0.0, 5.0), DVec3::NEG_Y),
    )
}

fn blob(
    g: &mut Gaussians<f64>,
    at: [f64; 3],
    scale: f64,
    opacity: f64,
    rgb: [f64; 3],
    pop: Population,
) {
    let dc = rgb.map(|c| (c - 0.5) / C0);
    let mut sh = vec![[0.0; 3]; g.sh_coeffs()];
    sh[0] = dc;
    // Some view dependence, which the mirrored copy must turn with the mirror.
    if sh.len() > 3 {
        sh[3] = [0.2, -0.1, 0.05];
    }
    let l = scale.ln();
    let flat = if pop == Population::Glass { (0.01f64).ln() } else { l };
    g.push(at, [0.9, 0.1, -0.2, 0.3], [l, l, flat], (opacity / (1.0 - opacity)).ln(), &sh, pop);
}

/// A mirror at z = 5 facing cameras near the origin, its glass painted fully; coloured blobs
/// behind the cameras (seen only in the mirror), one behind the mirror (hidden by it in trgs's
/// render), and with `front_blob` one in front of it (seen directly and mirrored).
fn mirror_scene(front_blob: bool) -> (Gaussians<f64>, Vec<ReflectionPlane>) {
    let plane = ReflectionPlane::new(
        DVec3::new(0.0, 0.0, 5.0),
        DVec3::new(0.0, 0.0, -1.0),
        DVec3::X,
        5.0,
        4.0,
        Material::Mirror,
    );
    let mut g = Gaussians::<f64>::empty(1);
    for (i, x) in [-1.2, 0.0, 1.2].into_iter().enumerate() {
        let rgb = [[0.9, 0.2, 0.1], [0.1, 0.8, 0.2], [0.2, 0.3, 0.9]][i];
        blob(&mut g, [x, 0.3 * x, -3.0], 0.5, 0.95, rgb, Population::Primary);
    }
    if front_blob {
        blob(&mut g, [0.6, -0.5, 2.5], 0.25, 0.9, [0.9, 0.9, 0.2], Population::Primary);
    }
    blob(&mut g, [0.0, 0.0, 7.0], 1.0, 0.99, [0.9, 0.9, 0.9], Population::Primary);
    let mut m = 0;
    for iy in -4..=4 {
        for ix in -5..=5 {
            let at = [0.5 * f64::from(ix), 0.5 * f64::from(iy), 5.0];
            blob(&mut g, at, 0.35, 0.99, [0.5; 3], Population::Glass);
            m += 1;
        }
    }
    let n = g.len();
    for i in n - m..n {
        g.mask_logits[i] = 6.0;
    }
    (g, vec![plane])
}

fn to_f32(img: &Image<f64>) -> Image<f32> {
    img.map(|v| v as f32)
}

/// The plain render of the baked `mirror_scene` from a new view between the sampled ones, and of
/// the model as written without baking (glass as splats), each in PSNR against trgs's render.
fn baked_and_unbaked_psnr(front_blob: bool) -> (f64, f64, BakeReport) {
    let (g, planes) = mirror_scene(front_blob);
    let settings = RenderSettings::default();
    let cams: Vec<Camera> = [(-0.6, 0.0), (0.0, 0.0), (0.6, 0.3), (0.3, -0.4)]
        .iter()
        .enumerate()
        .map(|(i, &(x, y))| camera(&format!("v{i}"), DVec3::new(x, y, 0.0)))
        .collect();
    let strengths: Vec<Image<f32>> = cams
        .iter()
        .map(|c| to_f32(&render(&g, &planes, c, &settings).expect("render").strength))
        .collect();
    let views: Vec<StrengthView> = cams
        .iter()
        .zip(&strengths)
        .map(|(camera, strength)| StrengthView { camera, strength })
        .collect();
    let (baked, report) = bake(&g.cast(), &planes, &views);
    assert!(baked.populations.iter().all(|&p| p == Population::Primary));
    let novel = camera("novel", DVec3::new(0.25, 0.15, 0.2));
    let truth = to_f32(&render(&g, &planes, &novel, &settings).expect("render").color);
    let plain =
        |m: &Gaussians<f64>| to_f32(&render(m, &[], &novel, &settings).expect("render").color);
    let baked_psnr = psnr(&plain(&baked.cast()), &truth).expect("psnr");
    let unbaked_psnr = psnr(&plain(&g), &truth).expect("psnr");
    (baked_psnr, unbaked_psnr, report)
}

#[test]
fn a_baked_mirror_renders_in_a_plain_renderer_as_trgs_renders_it() {
    let (baked, unbaked, report) = baked_and_unbaked_psnr(false);
    assert_eq!(report.glass_left_out, 99);
    assert_eq!(report.mirrored, vec![3], "{report:?}");
    assert_eq!(report.dimmed, 1, "the blob behind the mirror: {report:?}");
    assert!(baked > 30.0 && baked > unbaked + 15.0, "baked {baked:.2} dB, unbaked {unbaked:.2}");
}

/// Where something in front of the glass half covers it, trgs's compose dims that thing by
/// `1 - R` as well (`R` is only partly occluded there), which no plain blend reproduces: the
/// baked render stays brighter along its silhouette.
#[test]
fn a_blob_in_front_of_a_baked_mirror_costs_only_its_silhouette() {
    let (baked, unbaked, report) = baked_and_unbaked_psnr(true);
    assert_eq!(report.mirrored, vec![4], "{report:?}");
    assert!(baked > 22.0 && baked > unbaked + 10.0, "baked {baked:.2} dB, unbaked {unbaked:.2}");
}

#[test]
fn without_planes_the_primaries_come_back_unchanged() {
    let (g, _) = mirror_scene(true);
    let g = g.cast::<f32>();
    let (baked, report) = bake(&g, &[], &[]);
    let primaries = g.subset(|i| g.populations[i] == Population::Primary);
    assert_eq!(baked.means, primaries.means);
    assert_eq!(baked.opacity_logits, primaries.opacity_logits);
    assert_eq!(baked.sh, primaries.sh);
    assert_eq!(report.glass_left_out, 99);
}

#[test]
fn a_mirrored_rotation_gives_the_mirrored_covariance() {
    let n = DVec3::new(0.2, 0.9, -0.3).normalize();
    let h = householder(n);
    let q = [0.7f32, -0.2, 0.5, 0.1];
    let s = DMat3::from_diagonal(DVec3::new(0.3, 1.2, 0.05));
    let rot = |q: [f32; 4]| {
        let [w, x, y, z] = q.map(f64::from);
        DMat3::from_quat(DQuat::from_xyzw(x, y, z, w).normalize())
    };
    let cov = |r: DMat3| r * s * s * r.transpose();
    let want = h * cov(rot(q)) * h;
    let got = cov(rot(mirrored_rotation(q, h)));
    assert!(want.abs_diff_eq(got, 1e-6), "{want:?} {got:?}");
}

#[test]
fn colour_scaling_scales_the_colour_in_every_direction() {
    let c = vec![[0.4, -0.3, 0.1], [0.1, 0.2, -0.1], [0.0, 0.05, 0.3], [-0.2, 0.1, 0.0]];
    let scaled = scaled_colour(&c, 0.6);
    for d in [[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.0, -1.0, 0.0]] {
        let (a, b) = (crate::sh::eval(1, &c, d), crate::sh::eval(1, &scaled, d));
        for ch in 0..3 {
            assert!((0.6 * a[ch] - b[ch]).abs() < 1e-12);
        }
    }
}
