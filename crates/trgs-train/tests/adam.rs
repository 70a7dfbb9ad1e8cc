//! The GPU Adam step against its twin (`trgs_core::reference::adam`, f64) over several steps, on
//! a buffer split into several binding ranges.
use trgs_core::pipeline::{AdamRate, AdamSettings};
use trgs_core::reference::adam;
use trgs_core::rng::Rng;
use trgs_render::toolkit::gpu::{self, Recorder};
use trgs_render::{DeviceOptions, GpuContext};
use trgs_train::stages::{Adam, AdamMoments};

#[test]
fn gpu_adam_matches_twin() {
    let ctx = GpuContext::with_options(&DeviceOptions {
        poison_fresh_buffers: true,
        ..Default::default()
    })
    .expect("adapter");
    let mut adam_gpu = Adam::new(&ctx, AdamSettings::default());
    // Not a multiple of 4: the kernel takes four floats a thread, and the last vec4's floats past
    // the count must keep what they held.
    let n = 5003usize;
    let mut rng = Rng::new(9);
    let mut params: Vec<f64> = (0..n).map(|_| f64::from(rng.range(-2.0, 2.0) as f32)).collect();
    let values = gpu::storage_init(
        &ctx,
        "test.values",
        &params.iter().map(|&v| v as f32).collect::<Vec<f32>>(),
    );
    let moments = AdamMoments::zeros(&ctx, "test", n as u64);
    let (mut m, mut v) = (vec![0.0; n], vec![0.0; n]);
    // Per float, the sum of its learning rates: a bound on how far its updates moved it.
    let mut step_sum = vec![0.0; n];
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
        // Large gradients past the count: a kernel that stepped the padding would move it.
        let padded: Vec<f32> = grads.iter().map(|&v| v as f32).chain([1e3; 13]).collect();
        let g_buf = gpu::storage_init(&ctx, "test.grads", &padded);
        // A rate pattern like the SH buffer's (records of 48 floats, the first 3 faster), whose
        // records straddle the binding ranges.
        let lr = 1e-3 * f64::from(t);
        let rate = AdamRate { lr, lead_lr: 20.0 * lr, lead: 3, stride: 48 };
        let mut rec = Recorder::new(&ctx, "test.adam", false);
        let open = trgs_train::stages::step_guard::open(&ctx);
        adam_gpu.record(&ctx, &mut rec, &values, &g_buf, &moments, &rate, t, &open);
        rec.submit_and_wait(&ctx).expect("GPU work");
        adam(&mut params, &grads, &mut m, &mut v, &rate, t, &adam_gpu.settings);
        for (i, s) in step_sum.iter_mut().enumerate() {
            *s += rate.at(i);
        }
    }
    let len = (values.size() / 4) as usize;
    let got: Vec<f32> = gpu::read_buffer(&ctx, &values, 0, len).expect("readback");
    assert!(got[n..].iter().all(|&v| v == 0.0), "floats past the count moved: {:?}", &got[n..]);
    // f32 rounding: a few ulps of the parameter, plus a relative error of the updates (1 - beta2
    // is 0.001 + 4.7e-8 in f32, which moves sqrt(v) by 2.3e-5 relative) times their size.
    let mut worst = 0.0f64;
    for i in 0..n {
        let err = (f64::from(got[i]) - params[i]).abs();
        let tol = 8.0 * f64::from(f32::EPSILON) * params[i].abs() + 1e-4 * step_sum[i];
        worst = worst.max(err / tol);
    }
    eprintln!("adam: worst error {worst:.2} of the tolerance");
    assert!(worst <= 1.0, "GPU Adam differs from the twin by {worst:.2} of the tolerance");
}
