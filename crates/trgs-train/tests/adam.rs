//! The GPU Adam step against its twin (`trgs_core::reference::adam`, f64) over several steps, on
//! a buffer split into several binding ranges.
use trgs_core::reference::{AdamSettings, adam};
use trgs_core::rng::Rng;
use trgs_render::gpu::{self, Recorder};
use trgs_render::{DeviceOptions, GpuContext};
use trgs_train::adam::{Adam, AdamMoments};

#[test]
fn gpu_adam_matches_twin() {
    let ctx = GpuContext::with_options(&DeviceOptions {
        poison_fresh_buffers: true,
        ..Default::default()
    })
    .expect("adapter");
    let mut adam_gpu = Adam::new(&ctx, AdamSettings::default());
    let n = 5000usize;
    let mut rng = Rng::new(9);
    let mut params: Vec<f64> = (0..n).map(|_| f64::from(rng.range(-2.0, 2.0) as f32)).collect();
    let values = gpu::storage_init(
        &ctx,
        "test.values",
        &params.iter().map(|&v| v as f32).collect::<Vec<f32>>(),
    );
    let moments = AdamMoments::zeros(&ctx, "test", n as u64);
    let (mut m, mut v) = (vec![0.0; n], vec![0.0; n]);
    adam_gpu.set_chunk(1024); // several binding ranges
    for t in 1..=6u32 {
        // Gradients of mixed sizes, including exact zeros.
        let grads: Vec<f64> = (0..n)
            .map(|i| {
                if i % 17 == 0 {
                    0.0
                } else {
                    f64::from((rng.normal() * 10f64.powf(rng.range(-4.0, 1.0))) as f32)
                }
            })
            .collect();
        let g_buf = gpu::storage_init(
            &ctx,
            "test.grads",
            &grads.iter().map(|&v| v as f32).collect::<Vec<f32>>(),
        );
        let lr = 1e-3 * f64::from(t);
        let mut rec = Recorder::new(&ctx, "test.adam", false);
        adam_gpu.record(&ctx, &mut rec, &values, &g_buf, &moments, lr, t);
        rec.submit_and_wait(&ctx);
        adam(&mut params, &grads, &mut m, &mut v, lr, t, &adam_gpu.settings);
    }
    let got: Vec<f32> = gpu::read_buffer(&ctx, &values, 0, n);
    // f32 rounding: a few ulps of the parameter (up to 2) plus a relative error of the updates.
    let worst =
        got.iter().zip(&params).map(|(&g, &c)| (f64::from(g) - c).abs()).fold(0.0f64, f64::max);
    eprintln!("adam: worst absolute difference {worst:.2e}");
    assert!(worst < 2e-6, "GPU Adam differs from the twin by {worst:.2e}");
}
