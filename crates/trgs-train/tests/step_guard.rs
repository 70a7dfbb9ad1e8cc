//! Stage `step_guard` against its twin, and what a set guard does to the updates that read it:
//! `adam` and `mcmc_noise` leave every value and moment as it was.
use trgs_core::pipeline::{AdamRate, AdamSettings, GUARD_KEYS_DROPPED};
use trgs_core::reference::step_guard;
use trgs_core::rng::Rng;
use trgs_core::scene::Gaussians;
use trgs_render::toolkit::gpu::{self, Recorder};
use trgs_render::{DeviceOptions, GpuContext, GpuScene};
use trgs_train::densify::mcmc::{McmcKernels, McmcSettings};
use trgs_train::stages::step_guard::StepGuard;
use trgs_train::stages::{Adam, AdamMoments};

fn ctx() -> GpuContext {
    GpuContext::with_options(&DeviceOptions { poison_fresh_buffers: true, ..Default::default() })
        .expect("adapter")
}

#[test]
fn gpu_step_guard_matches_twin() {
    let ctx = ctx();
    let guard = StepGuard::new(&ctx);
    // More sums than one workgroup takes; a bad value in the last vec4 and in the middle.
    let n = 700;
    let fine: Vec<[f32; 4]> = (0..n).map(|i| [i as f32, 1.0, -2.0, 0.5]).collect();
    let mut cases = vec![fine.clone()];
    for (at, bad) in [(n - 1, f32::NAN), (300, f32::INFINITY), (0, f32::NEG_INFINITY)] {
        let mut sums = fine.clone();
        sums[at][at % 4] = bad;
        cases.push(sums);
    }
    for sums in &cases {
        for dropped in [0u32, 1] {
            let sums_buf = gpu::storage_init(&ctx, "test.sums", sums);
            let kept = gpu::storage_init(&ctx, "test.kept", &[123u32, dropped]);
            let mut rec = Recorder::new(&ctx, "test.step_guard", false);
            // Set before: the stage clears it.
            let set = gpu::storage_init(&ctx, "test.set", &[0xffu32; 4]);
            rec.encoder.copy_buffer_to_buffer(&set, 0, guard.word(), 0, 16);
            guard.record(&ctx, &mut rec, &sums_buf, sums.len() as u32, &kept);
            rec.submit_and_wait(&ctx).expect("GPU work");
            let got: Vec<u32> = gpu::read_buffer(&ctx, guard.word(), 0, 1).expect("readback");
            assert_eq!(got[0], step_guard(dropped, sums), "dropped {dropped}");
        }
    }
}

#[test]
fn a_set_guard_leaves_adam_and_the_noise_alone() {
    let ctx = ctx();
    let set = gpu::storage_init(&ctx, "test.guard", &[GUARD_KEYS_DROPPED, 0, 0, 0]);
    let n = 1000usize;
    let mut rng = Rng::new(5);
    let values: Vec<f32> = (0..n).map(|_| rng.range(-2.0, 2.0) as f32).collect();
    let grads: Vec<f32> = (0..n).map(|_| rng.range(-1.0, 1.0) as f32).collect();
    let m: Vec<f32> = (0..n).map(|_| rng.range(-0.1, 0.1) as f32).collect();
    let v: Vec<f32> = (0..n).map(|_| rng.range(0.0, 0.1) as f32).collect();
    let values_buf = gpu::storage_init(&ctx, "test.values", &values);
    let grads_buf = gpu::storage_init(&ctx, "test.grads", &grads);
    let moments = AdamMoments::from_values(&ctx, "test", &m, &v);
    let adam = Adam::new(&ctx, AdamSettings::default());
    let rate = AdamRate::uniform(0.1);
    let mut rec = Recorder::new(&ctx, "test.adam", false);
    adam.record(&ctx, &mut rec, &values_buf, &grads_buf, &moments, &rate, 3, &set);
    rec.submit_and_wait(&ctx).expect("GPU work");
    let read =
        |b: &wgpu::Buffer| -> Vec<f32> { gpu::read_buffer(&ctx, b, 0, n).expect("readback") };
    assert_eq!(read(&values_buf), values, "adam moved values under a set guard");
    assert_eq!(read(&moments.m), m, "adam moved first moments under a set guard");
    assert_eq!(read(&moments.v), v, "adam moved second moments under a set guard");

    let mut g = Gaussians::<f32>::zeros(200, 1);
    for i in 0..200 {
        g.means[i] = [rng.range(-1.0, 1.0) as f32, rng.range(-1.0, 1.0) as f32, 3.0];
        g.rotations[i] = [1.0, 0.0, 0.0, 0.0];
        g.log_scales[i] = [-3.0; 3];
        // Transparent: the noise moves these most.
        g.opacity_logits[i] = -8.0;
    }
    let scene = GpuScene::upload(&ctx, &g, &[]).expect("valid scene");
    let kernels = McmcKernels::new(&ctx);
    let settings = McmcSettings::scaled(30_000, 1_000);
    let mut rec = Recorder::new(&ctx, "test.mcmc", false);
    let lr = AdamRate::uniform(1.0);
    kernels.record_noise(&ctx, &mut rec, &scene, &settings, &lr, 9, &set);
    rec.submit_and_wait(&ctx).expect("GPU work");
    assert_eq!(scene.read(&ctx).expect("readback").means, g.means, "noise under a set guard");
}
