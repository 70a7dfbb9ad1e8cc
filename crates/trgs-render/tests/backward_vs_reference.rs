//! GPU adjoint stages against their CPU twins, stage by stage, on lavapipe (or whatever adapter
//! the machine has): the same forward frame and the same random upstream gradients in, gradients
//! within atol 1e-5 + rtol 1e-3 of the twin's out (plane sums relative to their scale). Each runs
//! twice: with the adapter's float atomics and subgroup reduction, and with the optional features
//! off (the compare-exchange fallback without subgroups). Fresh buffers are poison-filled.
use trgs_core::Image;
use trgs_core::fixtures::{SceneSpec, random_scene};
use trgs_core::reference::{self, FrameGrads, PlaneLayerGrads, RenderSettings, compose_bwd};
use trgs_core::rng::Rng;
use trgs_core::scene::Gaussians;
use trgs_render::gpu;
use trgs_render::stages::compose_bwd::LayerGrads;
use trgs_render::{DeviceOptions, GpuContext, GpuScene, RenderOptions, Renderer};

mod common;
use common::{compare_values, spec};

fn contexts() -> Vec<(&'static str, GpuContext)> {
    let fast = DeviceOptions { poison_fresh_buffers: true, ..Default::default() };
    let fallback = DeviceOptions { disable_optional_features: true, ..fast.clone() };
    vec![("native", fast), ("fallback", fallback)]
        .into_iter()
        .map(|(n, o)| (n, GpuContext::with_options(&o).unwrap_or_else(|e| panic!("{e}"))))
        .collect()
}

fn random_image(rng: &mut Rng, w: u32, h: u32, channels: u32) -> Image<f64> {
    let mut im = Image::new(w, h, channels);
    for v in &mut im.data {
        *v = rng.range(-1.0, 1.0);
    }
    im
}

/// Pixels of up to four single- or multi-channel images packed as vec4 per pixel.
fn pack(parts: &[(&Image<f64>, usize)]) -> Vec<[f32; 4]> {
    let (w, h) = (parts[0].0.width, parts[0].0.height);
    let mut out = vec![[0.0f32; 4]; (w * h) as usize];
    for &(im, first) in parts {
        for y in 0..h {
            for x in 0..w {
                for c in 0..im.channels {
                    out[(y * w + x) as usize][first + c as usize] = im.get(x, y, c) as f32;
                }
            }
        }
    }
    out
}

fn compare(what: &str, gpu: &[f32], cpu: &[f64]) -> usize {
    compare_values(what, gpu, cpu, 1)
}

fn channel(v: &[[f32; 4]], channels: std::ops::Range<usize>) -> Vec<f32> {
    v.iter().flat_map(|p| p[channels.clone()].to_vec()).collect()
}

fn check_compose_bwd(name: &str, spec: SceneSpec) {
    let scene = random_scene(&spec);
    let g32: Gaussians<f32> = scene.gaussians.cast();
    let g = g32.cast::<f64>();
    let background = [0.1, 0.2, 0.3];
    let settings = RenderSettings { background, ..Default::default() };
    let cpu_frame = reference::render(&g, &scene.planes, &scene.camera, &settings).expect("valid");
    let (w, h) = (cpu_frame.color.width, cpu_frame.color.height);
    let mut rng = Rng::new(spec.seed ^ 0x5eed);
    let grads = FrameGrads {
        color: random_image(&mut rng, w, h, 3),
        transmission: random_image(&mut rng, w, h, 3),
        depth: random_image(&mut rng, w, h, 1),
        depth_variance: random_image(&mut rng, w, h, 1),
        mask: random_image(&mut rng, w, h, 1),
        alpha: random_image(&mut rng, w, h, 1),
        strength_raw: random_image(&mut rng, w, h, 1),
        strength: random_image(&mut rng, w, h, 1),
        reflection: random_image(&mut rng, w, h, 3),
        planes: scene
            .planes
            .iter()
            .map(|_| PlaneLayerGrads {
                raw_color: random_image(&mut rng, w, h, 3),
                intensity: random_image(&mut rng, w, h, 1),
            })
            .collect(),
    };
    let cpu = compose_bwd(&scene.camera, &scene.planes, &cpu_frame, &grads);

    for (mode, ctx) in contexts() {
        let what = format!("{name} ({mode})");
        let renderer = Renderer::new(&ctx);
        let gpu_scene = GpuScene::upload(&ctx, &g32, &scene.planes).expect("valid scene");
        let options = RenderOptions {
            background: background.map(|v| v as f32),
            depth_variance: true,
            ..Default::default()
        };
        let frame = renderer.render(&gpu_scene, &scene.camera, &options).expect("render");
        let hit = frame.read_images(&ctx).hit;
        let differing = hit.data.iter().zip(&cpu_frame.hit.data).filter(|(a, b)| a != b).count();
        assert_eq!(differing, 0, "{what}: hit masks differ");

        let slots = frame.plane_slots();
        let mut raw = Vec::new();
        for k in 0..slots {
            match grads.planes.get(k) {
                Some(p) => raw.extend(pack(&[(&p.raw_color, 0), (&p.intensity, 3)])),
                None => raw.extend(vec![[0.0f32; 4]; (w * h) as usize]),
            }
        }
        let zero = Image::<f64>::new(w, h, 1);
        let buffers = LayerGrads {
            color: gpu::storage_init(&ctx, "test.g_color", &pack(&[(&grads.color, 0)])),
            reflection: gpu::storage_init(
                &ctx,
                "test.g_reflection",
                &pack(&[(&grads.reflection, 0)]),
            ),
            strength: gpu::storage_init(
                &ctx,
                "test.g_strength",
                &pack(&[(&grads.strength_raw, 0), (&grads.strength, 1)]),
            ),
            transmission: gpu::storage_init(
                &ctx,
                "test.g_transmission",
                &pack(&[(&grads.transmission, 0), (&grads.alpha, 3)]),
            ),
            geometry: gpu::storage_init(
                &ctx,
                "test.g_geometry",
                &pack(&[
                    (&grads.depth, 0),
                    (&grads.depth_variance, 1),
                    (&grads.mask, 2),
                    (&zero, 3),
                ]),
            ),
            reflection_raw: gpu::storage_init(&ctx, "test.g_reflection_raw", &raw),
        };
        let plane_grads = renderer.compose_bwd(&frame, &buffers);
        let n = (w * h) as usize;
        let t: Vec<[f32; 4]> = gpu::read_buffer(&ctx, &buffers.transmission, 0, n);
        let geo: Vec<[f32; 4]> = gpu::read_buffer(&ctx, &buffers.geometry, 0, n);
        let mut bad = compare(&format!("{what} dC_t"), &channel(&t, 0..3), &cpu.transmission.data);
        bad += compare(&format!("{what} dalpha"), &channel(&t, 3..4), &grads.alpha.data);
        bad += compare(&format!("{what} dD_t"), &channel(&geo, 0..1), &grads.depth.data);
        bad += compare(&format!("{what} dV"), &channel(&geo, 1..2), &grads.depth_variance.data);
        bad += compare(&format!("{what} dM"), &channel(&geo, 2..3), &cpu.mask.data);
        let r: Vec<[f32; 4]> = gpu::read_buffer(&ctx, &buffers.reflection_raw, 0, n * slots);
        for (k, (g_raw, g_int)) in cpu.planes.iter().enumerate() {
            let slot = &r[k * n..(k + 1) * n];
            bad += compare(&format!("{what} plane {k} dC_raw"), &channel(slot, 0..3), &g_raw.data);
            bad += compare(&format!("{what} plane {k} dA"), &channel(slot, 3..4), &g_int.data);
        }
        assert_eq!(bad, 0, "{what}: per-pixel gradients");
        // Plane sums over all pixels: relative to the largest term's scale.
        assert_eq!(plane_grads.len(), scene.planes.len());
        for (k, gp) in plane_grads.iter().enumerate() {
            let want =
                [cpu.r0[k], cpu.unit_normal[k].x, cpu.unit_normal[k].y, cpu.unit_normal[k].z];
            let scale = want.iter().fold(1e-3f64, |m, v| m.max(v.abs()));
            for (c, (&a, &b)) in gp.iter().zip(&want).enumerate() {
                let err = (f64::from(a) - b).abs() / scale;
                eprintln!("{what} plane {k} grad {c}: gpu {a} cpu {b} (relative {err:.2e})");
                assert!(err <= 1e-4, "{what}: plane {k} gradient {c}: gpu {a} cpu {b}");
            }
        }
    }
}

#[test]
fn compose_bwd_no_plane() {
    check_compose_bwd("no plane", spec(41, 600, 0, 20.0));
}

#[test]
fn compose_bwd_one_plane() {
    check_compose_bwd("1 plane", spec(42, 600, 1, 25.0));
}

#[test]
fn compose_bwd_two_planes() {
    check_compose_bwd("2 planes", spec(43, 600, 2, 30.0));
}

#[test]
fn compose_bwd_grazing() {
    check_compose_bwd("80 deg", spec(44, 600, 1, 80.0));
}
