//! Stage `gather_rows` (densification's rebuild of the Gaussians and their Adam moments on the
//! GPU) against its twin `RowPlan::apply`, bit for bit: random plans over a scene with SH degree
//! 3 and glass Gaussians, in one binding range and in many; then classic densification and MCMC
//! relocation through the trainer against the whole state read back and rebuilt on the CPU.
use trgs_core::fixtures::{SceneSpec, random_scene};
use trgs_core::rng::Rng;
use trgs_core::scene::{Attribute, Gaussians, PerAttribute, ReflectionPlane, attribute_widths};
use trgs_render::toolkit::gpu::read_buffer;
use trgs_render::{DeviceOptions, GpuContext, GpuScene};
use trgs_train::TrainSettings;
use trgs_train::Trainer;
use trgs_train::checkpoint::Checkpoint;
use trgs_train::densify::mcmc::{McmcDensification, McmcSettings, plan_relocation};
use trgs_train::densify::{ClassicDensification, Densification};
use trgs_train::densify::{ClassicSettings, DensifyStats, classic::plan_densify};
use trgs_train::stages::AdamMoments;
use trgs_train::stages::GpuRowGather;
use trgs_train::stages::{Geometry, RowPlan, TrainState};

fn ctx() -> GpuContext {
    GpuContext::with_options(&DeviceOptions { poison_fresh_buffers: true, ..Default::default() })
        .expect("adapter")
}

/// A scene of `n` Gaussians (SH degree 3, 10% glass, two planes) with moments that differ in
/// every word, so that a wrong row or a moment kept where it should restart shows.
fn state(n: usize, seed: u64) -> (TrainState, Vec<ReflectionPlane>) {
    let spec = SceneSpec {
        seed,
        gaussians: n,
        planes: 2,
        width: 64,
        height: 48,
        view_angle_deg: 30.0,
        sh_degree: 3,
        glass_fraction: 0.1,
    };
    let scene = random_scene(&spec);
    let g: Gaussians<f32> = scene.gaussians.cast();
    let w = attribute_widths(g.sh_coeffs());
    let moments = |base: f32| {
        PerAttribute::from_fn(|a| {
            (0..n * w[a]).map(|k| base + (a.index() * 100_000 + k) as f32).collect()
        })
    };
    (TrainState { m: moments(0.5), v: moments(-0.25), gaussians: g }, scene.planes)
}

/// A plan that drops, repeats and reorders rows, restarts some moments and gives some attributes.
fn random_plan(n: usize, rng: &mut Rng, give: bool) -> RowPlan {
    let rows = n + n / 3;
    let sources: Vec<(usize, bool)> =
        (0..rows).map(|_| (rng.below(n), rng.uniform() < 0.7)).collect();
    let value = |rng: &mut Rng| rng.range(-3.0, 3.0) as f32;
    RowPlan {
        means: give.then(|| (0..rows).map(|_| [value(rng), value(rng), value(rng)]).collect()),
        log_scales: give.then(|| (0..rows).map(|_| [value(rng), value(rng), value(rng)]).collect()),
        opacity_logits: give.then(|| (0..rows).map(|_| value(rng)).collect()),
        sources,
    }
}

fn upload(
    ctx: &GpuContext,
    s: &TrainState,
    planes: &[ReflectionPlane],
) -> (GpuScene, PerAttribute<AdamMoments>) {
    let scene = GpuScene::upload(ctx, &s.gaussians, planes).expect("valid scene");
    let moments =
        PerAttribute::from_fn(|a| AdamMoments::from_values(ctx, "test", &s.m[a], &s.v[a]));
    (scene, moments)
}

fn read_back(
    ctx: &GpuContext,
    scene: &GpuScene,
    moments: &PerAttribute<AdamMoments>,
) -> TrainState {
    let read = |b: &wgpu::Buffer, len: u64| -> Vec<f32> {
        read_buffer(ctx, b, 0, len as usize).expect("readback")
    };
    TrainState {
        gaussians: scene.read(ctx).expect("readback"),
        m: moments.as_ref().map(|mo| read(&mo.m, mo.len)),
        v: moments.as_ref().map(|mo| read(&mo.v, mo.len)),
    }
}

fn assert_same(gpu: &TrainState, twin: &TrainState, what: &str) {
    assert_eq!(gpu.gaussians.len(), twin.gaussians.len(), "{what}: count");
    assert!(gpu.gaussians == twin.gaussians, "{what}: the Gaussians differ");
    for a in Attribute::ALL {
        assert!(gpu.m[a] == twin.m[a], "{what}: first moments of {a:?} differ");
        assert!(gpu.v[a] == twin.v[a], "{what}: second moments of {a:?} differ");
    }
}

#[test]
fn gather_rows_matches_twin_in_one_range_and_in_many() {
    let ctx = ctx();
    let (s, planes) = state(1000, 3);
    let (scene, moments) = upload(&ctx, &s, &planes);
    let mut rng = Rng::new(11);
    // 640 words a binding: every buffer, the moments included, takes several ranges (the SH
    // buffer's 48-word rows one range per 64 rows), and the sources span several too.
    for binding_words in [None, Some(640)] {
        let mut gather = GpuRowGather::new(&ctx);
        if let Some(w) = binding_words {
            gather.set_binding_words(w);
        }
        for give in [false, true] {
            let plan = random_plan(1000, &mut rng, give);
            let (scene2, moments2) = gather.apply(&ctx, &scene, &moments, &plan).expect("rebuild");
            let what = format!("binding {binding_words:?}, given attributes {give}");
            assert_same(&read_back(&ctx, &scene2, &moments2), &plan.apply(&s), &what);
        }
    }
    // Everything pruned: an empty set.
    let gather = GpuRowGather::new(&ctx);
    let (empty, moments0) =
        gather.apply(&ctx, &scene, &moments, &RowPlan::default()).expect("rebuild");
    assert_eq!(empty.len(), 0);
    assert!(moments0.iter().all(|(_, m)| m.len == 0));
}

/// Two trainers in the same state (a checkpoint) with classic densification statistics.
fn trainers(ctx: &GpuContext) -> (Trainer, Trainer, Checkpoint) {
    let (mut s, planes) = state(1500, 5);
    let n = s.gaussians.len();
    let mut rng = Rng::new(9);
    // Sizes on both sides of the clone/split line (1% of the extent) and of the prune line
    // (10%), and opacities down to dead ones (MCMC relocates those at or below 0.005).
    for i in 0..n {
        let l = rng.range(-7.0, -1.5) as f32;
        s.gaussians.log_scales[i] = [l, l - 0.3, l - 0.6];
        s.gaussians.opacity_logits[i] = rng.range(-8.0, 4.0) as f32;
    }
    let mut stats = DensifyStats::new(n);
    for i in 0..n {
        stats.count[i] = rng.below(4) as u32;
        stats.grad_sum[i] = rng.range(0.0, 1e-3);
        stats.max_radius[i] = rng.range(0.0, 30.0);
    }
    let ck = Checkpoint {
        step: 700,
        state: s,
        planes,
        plane_moments: Vec::new(),
        exposures: Default::default(),
        densify_stats: Some(stats),
        rng_state: 0x1234_5678,
        extra: serde_json::Value::Null,
    };
    let settings = TrainSettings::scaled(30_000);
    let mut densify = ClassicSettings::scaled(30_000);
    densify.max_screen_radius = 20.0;
    densify.prune_scale = 0.1; // 3DGS's world-size prune too (off by default)
    let make = || {
        let s = settings.clone();
        let classic = Densification::Classic(densify.clone());
        Trainer::from_checkpoint(ctx, &ck, s, 1.0, &classic).expect("trainer")
    };
    (make(), make(), ck)
}

#[test]
fn densification_on_the_gpu_matches_the_cpu_rebuild() {
    let ctx = ctx();
    let (mut gpu, mut cpu, ck) = trainers(&ctx);
    assert_eq!(
        gpu.geometry().expect("readback"),
        Geometry::of(&ck.state.gaussians),
        "the geometry read back"
    );
    let stats = ck.densify_stats.as_ref().expect("statistics");
    let settings = {
        let mut d = ClassicSettings::scaled(30_000);
        d.max_screen_radius = 20.0;
        d.prune_scale = 0.1;
        d
    };
    let n = ck.state.gaussians.len();
    let mut classic = ClassicDensification::resumed(&ctx, settings.clone(), n, Some(stats));
    // Decided on the CPU here, so that the rebuild is compared bit for bit (tests/densify_plan.rs
    // checks the decisions made on the GPU).
    classic.decide_on_cpu();
    let report = gpu
        .edit_gaussians(|g, rng, extent| classic.densify_now(g, rng, extent, true))
        .expect("densify on the GPU");
    let mut rng = Rng::from_state(ck.rng_state);
    let geometry = Geometry::of(&ck.state.gaussians);
    let (plan, twin_report) = plan_densify(&geometry, stats, &settings, 1.0, true, &mut rng);
    assert_eq!(report, twin_report);
    assert!(report.cloned > 0 && report.split > 0 && report.pruned > 0, "{report:?}");
    cpu.apply_plan_on_cpu(&plan).expect("rebuild on the CPU");
    assert_same(
        &gpu.read_state().expect("readback"),
        &cpu.read_state().expect("readback"),
        "classic densification",
    );
    // The statistics start over for the new set.
    let after = gpu
        .checkpoint(serde_json::Value::Null)
        .expect("readback")
        .densify_stats
        .expect("statistics");
    assert_eq!(after.count, vec![0; plan.sources.len()]);
}

#[test]
fn relocation_on_the_gpu_matches_the_cpu_rebuild() {
    let ctx = ctx();
    let (mut gpu, mut cpu, ck) = trainers(&ctx);
    let settings = McmcSettings::scaled(30_000, 1600);
    let mut mcmc = McmcDensification::new(&ctx, settings.clone());
    // Decided on the CPU here (tests/mcmc_relocate.rs checks the decisions made on the GPU).
    mcmc.decide_on_cpu();
    let report = gpu.edit_gaussians(|g, rng, _| mcmc.relocate_now(g, rng)).expect("relocate");
    let mut rng = Rng::from_state(ck.rng_state);
    let geometry = Geometry::of(&ck.state.gaussians);
    let (plan, twin_report) = plan_relocation(&geometry, &settings, &mut rng);
    assert_eq!(report, twin_report);
    assert!(report.relocated > 0 && report.added > 0, "{report:?}");
    cpu.apply_plan_on_cpu(&plan).expect("rebuild on the CPU");
    assert_same(
        &gpu.read_state().expect("readback"),
        &cpu.read_state().expect("readback"),
        "MCMC relocation",
    );
}

#[test]
fn a_plan_that_breaks_the_set_is_refused() {
    let ctx = ctx();
    let (mut t, _, _) = trainers(&ctx);
    let n = t.scene().len() as usize;
    let out_of_range = RowPlan { sources: vec![(n, true)], ..RowPlan::default() };
    assert!(t.apply_plan(&out_of_range).is_err());
    let short =
        RowPlan { sources: vec![(0, true); 2], means: Some(vec![[0.0; 3]]), ..RowPlan::default() };
    assert!(t.apply_plan(&short).is_err());
    let infinite = RowPlan {
        sources: vec![(0, true)],
        opacity_logits: Some(vec![f32::INFINITY]),
        ..RowPlan::default()
    };
    let err = t.apply_plan(&infinite).expect_err("a non-finite opacity");
    assert!(err.to_string().contains("non-finite"), "{err}");
    assert_eq!(t.scene().len() as usize, n, "a refused plan leaves the set as it was");
}
