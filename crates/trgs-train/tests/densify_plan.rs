//! Stage `densify_plan` (classic densification decided on the GPU) against its twin
//! `plan_densify` applied on the CPU: the report, every row's source, every parameter and Adam
//! moment bit for bit, and the split children's means within f32 rounding of the twin's f64.
//! Hard cases: a scan of several blocks, the room under `max_gaussians` running out part way,
//! the size prune on and off, a set pruned to nothing, an empty set, and a growth share.
mod common;

use trgs_core::rng::Rng;
use trgs_core::scene::Attribute;
use trgs_render::{DeviceOptions, GpuContext};
use trgs_train::densify::classic::plan_densify;
use trgs_train::densify::{ClassicDensification, ClassicSettings, DensifyReport, DensifyStats};
use trgs_train::stages::GaussianState;
use trgs_train::stages::{Geometry, TrainState};

fn ctx() -> GpuContext {
    GpuContext::with_options(&DeviceOptions { poison_fresh_buffers: true, ..Default::default() })
        .expect("adapter")
}

/// A set (`common::random_state`) with statistics on both sides of the gradient threshold; a
/// quarter of it unseen (no gradient).
fn case(n: usize, seed: u64) -> (TrainState, DensifyStats) {
    let (state, mut rng) = common::random_state(n, seed, (-8.0, 4.0));
    let mut stats = DensifyStats::new(n);
    for i in 0..n {
        stats.count[i] = rng.below(4) as u32;
        let sum = f64::from(rng.range(0.0, 1e-3) as f32);
        stats.grad_sum[i] = if stats.count[i] > 0 { sum } else { 0.0 };
        stats.max_radius[i] = f64::from(rng.range(0.0, 30.0) as f32);
    }
    (state, stats)
}

/// Densify `state` on the GPU and by the twin; compare; the report.
fn check(
    ctx: &GpuContext,
    state: &TrainState,
    stats: &DensifyStats,
    settings: &ClassicSettings,
    prune_large: bool,
) -> DensifyReport {
    let (extent, seed) = (1.0, 77);
    let mut gpu = GaussianState::from_state(ctx, state, &[]).expect("upload");
    let n = state.gaussians.len();
    let mut classic = ClassicDensification::resumed(ctx, settings.clone(), n, Some(stats));
    let read_before = ctx.bytes_read();
    let report = classic
        .densify_now(&mut gpu, &mut Rng::new(seed), extent, prune_large)
        .expect("densify on the GPU");
    // Decided on the GPU: only the five counters (cloned, split, pruned, rows, seen) come back,
    // and the statistics where a growth share ranks the candidates.
    if settings.grow_fraction >= 1.0 {
        assert_eq!(ctx.bytes_read() - read_before, 20, "bytes read back to densify");
    }
    let geometry = Geometry::of(&state.gaussians);
    let (plan, twin_report) =
        plan_densify(&geometry, stats, settings, extent, prune_large, &mut Rng::new(seed));
    assert_eq!(report, twin_report, "the report");
    let twin = plan.apply(state);
    let got = gpu.read().expect("readback");
    let (a, b) = (&got.gaussians, &twin.gaussians);
    assert_eq!(a.len(), b.len(), "the count");
    assert_eq!(a.len(), n + report.cloned + report.split - report.pruned);
    for a_ in Attribute::ALL {
        assert!(got.m[a_] == twin.m[a_], "first moments of {a_:?}");
        assert!(got.v[a_] == twin.v[a_], "second moments of {a_:?}");
    }
    assert!(a.rotations == b.rotations && a.sh == b.sh, "rotations or colours");
    assert!(a.opacity_logits == b.opacity_logits && a.populations == b.populations);
    assert!(a.log_scales == b.log_scales, "log scales (the children's lose ln 1.6 in f32)");
    assert!(a.mask_logits == b.mask_logits && a.log_reflections == b.log_reflections);
    // A child's offset from its parent, s * z rotated, within f32 rounding of the twin's.
    let mut children = 0;
    for (j, &(src, _)) in plan.sources.iter().enumerate() {
        let parent = state.gaussians.means[src];
        if b.means[j] == parent {
            assert_eq!(a.means[j], parent, "row {j} is a copy of {src}");
            continue;
        }
        children += 1;
        let offset = |m: [f32; 3]| [0, 1, 2].map(|c| f64::from(m[c]) - f64::from(parent[c]));
        let (d, t) = (offset(a.means[j]), offset(b.means[j]));
        let size = t.iter().map(|v| v * v).sum::<f64>().sqrt();
        let scale = f64::from(state.gaussians.log_scales[src][0]).exp();
        for c in 0..3 {
            let tol = 1e-4 * size + 1e-6 * (1.0 + f64::from(parent[c].abs())) + 1e-4 * scale;
            assert!((d[c] - t[c]).abs() <= tol, "child row {j} of {src}: {d:?} vs {t:?}");
        }
    }
    let survivors = plan.sources.iter().filter(|&&(_, keep)| keep).count();
    assert_eq!(children, plan.sources.len() - survivors - report.cloned, "children moved");
    report
}

#[test]
fn the_gpu_decides_as_the_twin_does() {
    let ctx = ctx();
    let mut settings = ClassicSettings::scaled(30_000);
    settings.max_screen_radius = 20.0;
    settings.prune_scale = 0.1; // 3DGS's world-size prune (off by default)
    // 9000 Gaussians: more than two blocks of the scans on every adapter.
    let (state, stats) = case(9000, 5);
    for prune_large in [false, true] {
        let r = check(&ctx, &state, &stats, &settings, prune_large);
        println!("prune_large {prune_large}: {r:?}");
        assert!(r.cloned > 100 && r.split > 100 && r.pruned > 100, "{r:?}");
    }
    // No world-size prune (the default): its bound reaches the GPU as f32::MAX, and the plan
    // still agrees.
    settings.prune_scale = f64::INFINITY;
    let r = check(&ctx, &state, &stats, &settings, true);
    println!("no world-size prune: {r:?}");
    assert!(r.cloned > 100 && r.split > 100, "{r:?}");
}

#[test]
fn the_room_goes_to_the_first_candidates() {
    let ctx = ctx();
    let (state, stats) = case(5000, 8);
    let mut settings = ClassicSettings::scaled(30_000);
    settings.max_gaussians = 5000 + 37;
    let r = check(&ctx, &state, &stats, &settings, false);
    assert_eq!(r.cloned + r.split, 37, "{r:?}");
    // No room at all: nothing densifies, transparent Gaussians are still pruned.
    settings.max_gaussians = 10;
    let r = check(&ctx, &state, &stats, &settings, false);
    assert_eq!((r.cloned, r.split), (0, 0));
    assert!(r.pruned > 0);
}

#[test]
fn a_set_pruned_to_nothing_and_an_empty_set() {
    let ctx = ctx();
    let settings = ClassicSettings::scaled(30_000);
    let (mut state, stats) = case(300, 9);
    state.gaussians.opacity_logits.iter_mut().for_each(|o| *o = -20.0);
    let r = check(&ctx, &state, &stats, &settings, true);
    assert_eq!((r.cloned, r.split, r.pruned), (0, 0, 300));
    let (empty, stats) = case(0, 10);
    let r = check(&ctx, &empty, &stats, &settings, true);
    assert_eq!(r, DensifyReport::default());
}

#[test]
fn a_growth_share_densifies_about_that_share() {
    let ctx = ctx();
    let (state, stats) = case(9000, 11);
    let mut settings = ClassicSettings::scaled(30_000);
    let all = check(&ctx, &state, &stats, &settings, false);
    settings.grow_fraction = 0.25;
    let share = check(&ctx, &state, &stats, &settings, false);
    let (all, share) = (all.cloned + all.split, share.cloned + share.split);
    println!("densified: {all} of all candidates, {share} under a share of 0.25");
    // The candidates are ranked before the transparent ones are left out, which the case draws
    // whatever their gradient: about a quarter densify.
    assert!(all > 1000, "{all}");
    assert!(share * 10 >= all * 2 && share * 10 <= all * 3, "{share} of {all}");
}
