//! The GPU's `compose_bwd` stage against its CPU twin (`trgs_core::reference::compose_bwd`), on
//! lavapipe (or whatever adapter the machine has): the same forward frame and the same random
//! upstream gradients in, the layers' gradients within atol 1e-5 + rtol 1e-3 of the twin's out,
//! in each of `common::contexts`' layouts and with the optional features off. The other adjoint
//! stages: backward_vs_reference.rs.
use trgs_core::Image;
use trgs_core::fixtures::{SceneSpec, random_scene};
use trgs_core::pipeline::{ReflectionModel, RenderSettings};
use trgs_core::reference::{self, compose_bwd};
use trgs_core::scene::Gaussians;
use trgs_render::toolkit::gpu;
use trgs_render::{GpuScene, LayerGrads, RenderOptions, Renderer};

mod common;
use common::{channel, compare, contexts, pack, random_grads, spec};

fn check_compose_bwd(name: &str, spec: SceneSpec) {
    check_compose_bwd_model(name, spec, ReflectionModel::default());
}

fn check_compose_bwd_model(name: &str, spec: SceneSpec, model: ReflectionModel) {
    let scene = random_scene(&spec);
    let g32: Gaussians<f32> = scene.gaussians.cast();
    let g = g32.cast::<f64>();
    let background = [0.1, 0.2, 0.3];
    let settings = RenderSettings { background, reflection: model, ..Default::default() };
    let cpu_frame = reference::render(&g, &scene.planes, &scene.camera, &settings).expect("valid");
    let (w, h) = (cpu_frame.color.width, cpu_frame.color.height);
    let grads = random_grads(spec.seed ^ 0x5eed, &cpu_frame, scene.planes.len());
    let cpu = compose_bwd(&scene.camera, &scene.planes, &cpu_frame, &grads, model);

    for (mode, ctx) in contexts() {
        let what = format!("{name} ({mode})");
        let renderer = Renderer::new(&ctx);
        let gpu_scene = GpuScene::upload(&ctx, &g32, &scene.planes).expect("valid scene");
        let options = RenderOptions {
            background: background.map(|v| v as f32),
            depth_variance: true,
            reflection: model,
            ..Default::default()
        };
        let frame = renderer.render(&gpu_scene, &scene.camera, &options).expect("render");
        let images = frame.read_images(&ctx).expect("readback");
        let differing =
            images.hit.data.iter().zip(&cpu_frame.hit.data).filter(|(a, b)| a != b).count();
        assert_eq!(differing, 0, "{what}: hit masks differ");
        // The forward composition follows the same reflection model.
        let fwd = compare(&format!("{what} C"), &images.color.data, &cpu_frame.color.data)
            + compare(&format!("{what} R"), &images.strength.data, &cpu_frame.strength.data);
        assert_eq!(fwd, 0, "{what}: composed layers");

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
            size: (w, h),
        };
        let plane_grads = renderer.compose_bwd(&frame, &buffers).expect("readback");
        let n = (w * h) as usize;
        let t: Vec<[f32; 4]> =
            gpu::read_buffer(&ctx, &buffers.transmission, 0, n).expect("readback");
        let geo: Vec<[f32; 4]> = gpu::read_buffer(&ctx, &buffers.geometry, 0, n).expect("readback");
        let mut bad = compare(&format!("{what} dC_t"), &channel(&t, 0..3), &cpu.transmission.data);
        bad += compare(&format!("{what} dalpha"), &channel(&t, 3..4), &grads.alpha.data);
        bad += compare(&format!("{what} dD_t"), &channel(&geo, 0..1), &grads.depth.data);
        bad += compare(&format!("{what} dV"), &channel(&geo, 1..2), &grads.depth_variance.data);
        bad += compare(&format!("{what} dM"), &channel(&geo, 2..3), &cpu.mask.data);
        let r: Vec<[f32; 4]> =
            gpu::read_buffer(&ctx, &buffers.reflection_raw, 0, n * slots).expect("readback");
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

/// The ablations' reflection models: R_raw = R0 (no normal gradient through Schlick) and
/// C_r = C_raw (no gradient into A).
#[test]
fn compose_bwd_ablation_models() {
    for (fresnel, intensity) in [(false, true), (true, false)] {
        let model = ReflectionModel { fresnel, intensity };
        check_compose_bwd_model(&format!("{model:?}"), spec(45, 600, 1, 40.0), model);
    }
}
