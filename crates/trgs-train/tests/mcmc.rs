//! The GPU stages of MCMC densification (`mcmc_regularise`, `mcmc_noise`) against their twins
//! (`trgs_core::reference`, f64), on a scene split into several binding ranges, with glass
//! Gaussians (which both must leave alone) and opacities on both sides of the noise gate.
use trgs_core::pipeline::AdamRate;
use trgs_core::reference::{mcmc_noise, mcmc_regularise};
use trgs_core::rng::Rng;
use trgs_core::scene::{Attribute, Gaussians, Population};
use trgs_render::toolkit::gpu::{self, Recorder};
use trgs_render::{DeviceOptions, GpuContext, GpuScene, SceneGradBuffers};
use trgs_train::densify::mcmc::{McmcKernels, McmcSettings};

fn scene(n: usize, rng: &mut Rng) -> Gaussians<f32> {
    let mut g = Gaussians::<f32>::zeros(n, 1);
    for i in 0..n {
        g.means[i] = [rng.range(-2.0, 2.0) as f32, rng.range(-2.0, 2.0) as f32, 3.0];
        let q = [rng.normal(), rng.normal(), rng.normal(), rng.normal()];
        g.rotations[i] = q.map(|v| v as f32);
        g.log_scales[i] = [0; 3].map(|_| rng.range(-4.0, 0.5) as f32);
        // Logits from opaque to far below the gate's threshold (o < 0.005).
        g.opacity_logits[i] = rng.range(-9.0, 4.0) as f32;
        if i % 7 == 0 {
            g.populations[i] = Population::Glass;
        }
    }
    g
}

#[test]
fn gpu_mcmc_stages_match_twins() {
    let ctx = GpuContext::with_options(&DeviceOptions {
        poison_fresh_buffers: true,
        ..Default::default()
    })
    .expect("adapter");
    let mut rng = Rng::new(21);
    let n = 3000;
    let g = scene(n, &mut rng);
    let mut gpu_scene = GpuScene::upload(&ctx, &g, &[]).expect("upload");
    gpu_scene.set_chunk_size(1024); // several binding ranges
    let kernels = McmcKernels::new(&ctx);
    let settings = McmcSettings::scaled(30_000, 1_000_000);
    let twin = g.cast::<f64>();

    // mcmc_regularise onto gradients that already hold values, with a few diverged scales among
    // the Gaussians (exp(log-scale) would overflow f32 without the regulariser's cap).
    let mut diverged = g.clone();
    for i in (1..n).step_by(97) {
        diverged.log_scales[i] = [95.0, 300.0, -300.0];
    }
    let mut reg_scene = GpuScene::upload(&ctx, &diverged, &[]).expect("upload");
    reg_scene.set_chunk_size(1024);
    let g_scales: Vec<f32> = (0..3 * n).map(|_| rng.normal() as f32 * 1e-3).collect();
    let g_opacity: Vec<f32> = (0..n).map(|_| rng.normal() as f32 * 1e-3).collect();
    let grads = SceneGradBuffers::zeros(&ctx, &reg_scene).expect("allocation");
    ctx.queue.write_buffer(
        grads.parameter(Attribute::LogScales),
        0,
        bytemuck::cast_slice(&g_scales),
    );
    ctx.queue.write_buffer(
        grads.parameter(Attribute::OpacityLogits),
        0,
        bytemuck::cast_slice(&g_opacity),
    );
    let mut rec = Recorder::new(&ctx, "test.mcmc", false);
    kernels.record_regularise(&ctx, &mut rec, &reg_scene, &grads, &settings);
    rec.submit_and_wait(&ctx).expect("GPU work");
    let mut want_o: Vec<f64> = g_opacity.iter().map(|&v| f64::from(v)).collect();
    let mut want_s: Vec<[f64; 3]> =
        g_scales.chunks(3).map(|c| [c[0], c[1], c[2]].map(f64::from)).collect();
    mcmc_regularise(
        &diverged.cast::<f64>(),
        settings.opacity_weight,
        settings.scale_weight,
        n,
        &mut want_o,
        &mut want_s,
    );
    let got_o: Vec<f32> =
        gpu::read_buffer(&ctx, grads.parameter(Attribute::OpacityLogits), 0, n).expect("readback");
    let got_s: Vec<f32> =
        gpu::read_buffer(&ctx, grads.parameter(Attribute::LogScales), 0, 3 * n).expect("readback");
    let close = |a: f32, b: f64| (f64::from(a) - b).abs() <= 1e-6 * b.abs() + 1e-12;
    for i in 0..n {
        assert!(close(got_o[i], want_o[i]), "opacity gradient {i}: {} vs {}", got_o[i], want_o[i]);
        for c in 0..3 {
            let (a, b) = (got_s[3 * i + c], want_s[i][c]);
            // Adam squares it in f32: that must stay finite too.
            assert!((a * a).is_finite() && close(a, b), "log-scale gradient {i},{c}: {a} vs {b}");
        }
    }

    // mcmc_noise with a rate large enough that most Gaussians move visibly.
    let lr = AdamRate::uniform(1.6e-4 * 2.0);
    let seed = 77;
    let mut rec = Recorder::new(&ctx, "test.mcmc", false);
    let open = trgs_train::stages::step_guard::open(&ctx);
    kernels.record_noise(&ctx, &mut rec, &gpu_scene, &settings, &lr, seed, &open);
    rec.submit_and_wait(&ctx).expect("GPU work");
    let mut want = twin.clone();
    mcmc_noise(&mut want, settings.noise_rate * lr.lr, seed);
    let got = gpu_scene.read(&ctx).expect("readback");
    let (mut moved, mut worst) = (0, 0.0f64);
    for i in 0..n {
        let largest =
            (0..3).map(|c| (want.means[i][c] - twin.means[i][c]).abs()).fold(0.0, f64::max);
        for c in 0..3 {
            let before = twin.means[i][c];
            let step = want.means[i][c] - before;
            let err = (f64::from(got.means[i][c]) - want.means[i][c]).abs();
            // f32: a few ulps of the mean, plus 0.1% of the Gaussian's largest step (Vulkan lets
            // cos and log err by about 1e-4 absolute, which a normal number near 0 turns into a
            // large relative error of one component).
            let tol = 4.0 * f64::from(f32::EPSILON) * before.abs() + 1e-3 * largest;
            worst = worst.max(err / tol);
            if step.abs() > 1e-3 {
                moved += 1;
            }
        }
        if g.populations[i] == Population::Glass {
            assert_eq!(got.means[i], g.means[i], "glass Gaussian {i} moved");
        }
    }
    eprintln!(
        "mcmc_noise: {moved} coordinates moved by over 1 mm, worst error {worst:.2} of the tolerance"
    );
    assert!(moved > n / 4, "the noise should move the transparent Gaussians: {moved}");
    assert!(worst <= 1.0, "GPU noise differs from the twin by {worst:.2} of the tolerance");
}

/// The planes' Gaussians added under MCMC keep the set within its cap: the least opaque of the
/// Gaussians already there make room, and the added ones are all kept.
#[test]
fn planes_added_under_mcmc_stay_within_the_cap() {
    use trgs_core::fixtures::{SceneSpec, random_scene};
    use trgs_train::TrainSettings;
    use trgs_train::Trainer;
    use trgs_train::densify::Densification;
    let ctx = GpuContext::new().expect("adapter");
    let mut rng = Rng::new(7);
    let mut old = scene(300, &mut rng);
    old.populations.iter_mut().for_each(|p| *p = Population::Primary);
    let fixture = random_scene(&SceneSpec { planes: 1, ..SceneSpec::default() });
    let mut added = scene(40, &mut rng);
    added.opacity_logits.iter_mut().for_each(|o| *o = -20.0);
    let mut trainer =
        Trainer::new(&ctx, &old, &[], TrainSettings::scaled(100), 1.0).expect("trainer");
    trainer.set_densification(&Densification::Mcmc(McmcSettings::scaled(100, 320))).expect("mcmc");
    let dropped = trainer.add_planes(&fixture.planes, &[None], &added).expect("add planes");
    assert_eq!(dropped, 20);
    let after = trainer.gaussians().expect("readback");
    assert_eq!(after.len(), 320);
    // Every added Gaussian is there (the last 40 rows), and the 20 dropped were the least opaque.
    assert_eq!(&after.means[280..], &added.means[..]);
    let mut logits = old.opacity_logits.clone();
    logits.sort_by(|a, b| b.total_cmp(a));
    let kept_least = after.opacity_logits[..280].iter().copied().fold(f32::INFINITY, f32::min);
    assert_eq!(kept_least, logits[279], "the most opaque 280 of the old are kept");
}
