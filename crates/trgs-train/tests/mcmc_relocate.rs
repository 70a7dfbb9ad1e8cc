//! Stage `mcmc_relocate` (3DGS-MCMC's relocation and growth decided on the GPU) against its twin
//! `plan_relocation` applied on the CPU, bit for bit: the report, every row's source, every
//! parameter and Adam moment. Hard cases: scans of several blocks, one live Gaussian drawn past
//! Eq. 9's largest share, every primary Gaussian dead (nothing to draw from), no primary
//! Gaussian at all (no growth), the cap reached, and an empty set.
mod common;

use trgs_core::rng::Rng;
use trgs_core::scene::{Attribute, Population};
use trgs_render::{DeviceOptions, GpuContext};
use trgs_train::densify::McmcReport;
use trgs_train::densify::mcmc::{McmcDensification, McmcSettings, plan_relocation};
use trgs_train::stages::GaussianState;
use trgs_train::stages::{Geometry, TrainState};

fn ctx() -> GpuContext {
    GpuContext::with_options(&DeviceOptions { poison_fresh_buffers: true, ..Default::default() })
        .expect("adapter")
}

/// A set (`common::random_state`) with opacities from dead (a quarter at or below 0.005) to
/// opaque.
fn case(n: usize, seed: u64) -> TrainState {
    common::random_state(n, seed, (-9.0, 4.0)).0
}

/// Relocate `state` on the GPU and by the twin; compare bit for bit; the report.
fn check(ctx: &GpuContext, state: &TrainState, settings: &McmcSettings) -> McmcReport {
    let seed = 31;
    let mut gpu = GaussianState::from_state(ctx, state, &[]).expect("upload");
    let mut mcmc = McmcDensification::new(ctx, settings.clone());
    let read_before = ctx.bytes_read();
    let report = mcmc.relocate_now(&mut gpu, &mut Rng::new(seed)).expect("relocate on the GPU");
    // Decided on the GPU: only the dead count and the two weight totals come back.
    assert_eq!(ctx.bytes_read() - read_before, 12, "bytes read back to relocate");
    let geometry = Geometry::of(&state.gaussians);
    let (plan, twin_report) = plan_relocation(&geometry, settings, &mut Rng::new(seed));
    assert_eq!(report, twin_report, "the report");
    let twin = plan.apply(state);
    let got = gpu.read().expect("readback");
    assert_eq!(got.gaussians.len(), twin.gaussians.len(), "the count");
    assert!(got.gaussians == twin.gaussians, "the Gaussians differ");
    for a in Attribute::ALL {
        assert!(got.m[a] == twin.m[a], "first moments of {a:?}");
        assert!(got.v[a] == twin.v[a], "second moments of {a:?}");
    }
    report
}

fn settings(cap: usize) -> McmcSettings {
    McmcSettings::scaled(30_000, cap)
}

#[test]
fn the_gpu_relocates_as_the_twin_does() {
    let ctx = ctx();
    // 9000 Gaussians: more than two blocks of the scans on every adapter.
    let state = case(9000, 5);
    let r = check(&ctx, &state, &settings(20_000));
    println!("{r:?}");
    assert!(r.relocated > 1000 && r.added == 450, "{r:?}");
    // At the cap: relocation alone.
    let r = check(&ctx, &state, &settings(9000));
    assert!(r.relocated > 1000 && r.added == 0, "{r:?}");
}

#[test]
fn one_live_gaussian_takes_every_draw() {
    let ctx = ctx();
    let mut state = case(400, 6);
    let g = &mut state.gaussians;
    g.populations.fill(Population::Primary);
    g.opacity_logits.fill(-8.0);
    g.opacity_logits[123] = 3.0;
    // 399 draws on one Gaussian: Eq. 9's share is clamped at its largest.
    let r = check(&ctx, &state, &settings(1000));
    assert_eq!(r, McmcReport { relocated: 399, added: 20 });
}

#[test]
fn nothing_to_draw_from() {
    let ctx = ctx();
    // Every primary Gaussian dead: none relocates, but they can still be drawn to grow.
    let mut state = case(500, 7);
    state.gaussians.opacity_logits.fill(-8.0);
    let r = check(&ctx, &state, &settings(1000));
    assert_eq!(r.relocated, 0);
    assert_eq!(r.added, 25);
    // Only glass: nothing moves and nothing grows.
    state.gaussians.populations.fill(Population::Glass);
    let r = check(&ctx, &state, &settings(1000));
    assert_eq!(r, McmcReport::default());
    let r = check(&ctx, &case(0, 8), &settings(1000));
    assert_eq!(r, McmcReport::default());
}

#[test]
fn a_relocation_applied_a_step_late_keeps_the_step_on_the_rows_it_keeps() {
    use trgs_train::densify::DensifyStrategy;
    use trgs_train::densify::classic::opacity_reset_cap;
    let ctx = ctx();
    let state = case(3000, 12);
    let settings = settings(4000);
    let step = (1..).find(|&t| settings.relocates_at(t)).expect("a relocation step");
    let mut gpu = GaussianState::from_state(&ctx, &state, &[]).expect("upload");
    let mut mcmc = McmcDensification::new(&ctx, settings.clone());
    // Decided now, applied later (as a pipelined loop does after the next step).
    let events = mcmc.maintain(step, &mut gpu, &mut Rng::new(41), 1.0).expect("decide");
    assert!(events.is_empty() && mcmc.pending());
    // Meanwhile the set changes in place: every opacity capped (standing for a step's update).
    gpu.opacity_reset(opacity_reset_cap()).expect("reset");
    let meanwhile = gpu.read().expect("readback");
    let events = mcmc.settle(&mut gpu).expect("apply");
    assert_eq!(events.len(), 1, "{events:?}");
    // The twin: decided from the set as it was, applied to the set as it is.
    let (plan, _) = plan_relocation(&Geometry::of(&state.gaussians), &settings, &mut Rng::new(41));
    let want = plan.apply(&meanwhile);
    let got = gpu.read().expect("readback");
    assert!(got.gaussians == want.gaussians, "the Gaussians differ");
    for a in Attribute::ALL {
        assert!(got.m[a] == want.m[a] && got.v[a] == want.v[a], "the moments of {a:?}");
    }
    // Kept rows kept the cap, which the plan's own values (from before it) do not have.
    let given = plan.opacity_logits.as_ref().expect("relocation gives opacities");
    let kept_changed = plan
        .sources
        .iter()
        .zip(given)
        .zip(&got.gaussians.opacity_logits)
        .filter(|&((&(_, keep), &planned), &now)| keep && planned != now)
        .count();
    assert!(kept_changed > 100, "only {kept_changed} kept rows changed meanwhile");
}
