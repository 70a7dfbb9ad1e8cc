//! Stages `exposure` and `exposure_bwd` against their twins (`trgs_core::reference::exposure`,
//! `exposure_bwd`): the exposed image, the colour gradient turned back in place, and the
//! strips' sums of dL/d(A, b), at sizes of one and of several strips and workgroups, with a
//! partial last strip.
use trgs_core::Image;
use trgs_core::pipeline::ExposureMatrix;
use trgs_core::reference::{exposure, exposure_bwd};
use trgs_core::rng::Rng;
use trgs_render::toolkit::gpu::{self, Recorder};
use trgs_render::{DeviceOptions, GpuContext};
use trgs_train::stages::ExposureKernels;

fn ctx() -> GpuContext {
    GpuContext::with_options(&DeviceOptions { poison_fresh_buffers: true, ..Default::default() })
        .expect("adapter")
}

fn random_vec4s(n: usize, lo: f64, hi: f64, rng: &mut Rng) -> Vec<[f32; 4]> {
    (0..n).map(|_| std::array::from_fn(|_| rng.range(lo, hi) as f32)).collect()
}

fn image_of(w: u32, h: u32, v: &[[f32; 4]]) -> Image<f64> {
    Image {
        width: w,
        height: h,
        channels: 4,
        data: v.iter().flatten().map(|&x| f64::from(x)).collect(),
    }
}

#[test]
fn gpu_exposure_and_its_adjoint_match_the_twins() {
    let ctx = ctx();
    let mut kernels = ExposureKernels::new(&ctx);
    let mut rng = Rng::new(7);
    for (w, h) in [(5, 3), (37, 29), (130, 70)] {
        let n = (w * h) as usize;
        let rendered = random_vec4s(n, -0.1, 1.1, &mut rng);
        let upstream = random_vec4s(n, -1e-3, 1e-3, &mut rng);
        let m: ExposureMatrix =
            std::array::from_fn(|_| std::array::from_fn(|_| rng.range(-0.3, 1.3)));
        let rendered_buf = gpu::storage_init(&ctx, "test.rendered", &rendered);
        let grad_buf = gpu::storage_init(&ctx, "test.grad", &upstream);
        let mut rec = Recorder::new(&ctx, "test.exposure", false);
        let exposed = kernels.record_exposure(&ctx, &mut rec, &rendered_buf, (w, h), &m);
        let pending =
            kernels.record_exposure_bwd(&ctx, &mut rec, &rendered_buf, &grad_buf, (w, h), &m);
        rec.submit_and_wait(&ctx).expect("GPU work");
        let got: Vec<[f32; 4]> = gpu::read_buffer(&ctx, &exposed, 0, n).expect("readback");
        let back: Vec<[f32; 4]> = gpu::read_buffer(&ctx, &grad_buf, 0, n).expect("readback");
        let sums: Vec<[f32; 4]> =
            gpu::read_buffer(&ctx, pending.partials(), 0, pending.vec4s() as usize)
                .expect("readback");
        let render = image_of(w, h, &rendered);
        let want = exposure(&render, &m);
        for (g, t) in got.iter().flatten().zip(&want.data) {
            assert!((f64::from(*g) - t).abs() < 1e-5, "{w}x{h}: exposed {g} against {t}");
        }
        let twin = exposure_bwd(&render, &m, &image_of(w, h, &upstream));
        for (g, t) in back.iter().flatten().zip(&twin.color.data) {
            assert!((f64::from(*g) - t).abs() < 1e-8, "{w}x{h}: dL/dC {g} against {t}");
        }
        let grad = pending.gradient_of(&sums);
        for (g, t) in grad.iter().flatten().zip(twin.matrix.iter().flatten()) {
            let scale = 1e-3 * (n as f64).sqrt();
            assert!((g - t).abs() < 1e-4 * scale, "{w}x{h}: dL/dm {g} against {t}");
        }
    }
}
