//! What the tests of the deciding stages (`densify_plan`, `mcmc_relocate`) share: a set of
//! Gaussians to decide on.
use trgs_core::fixtures::{SceneSpec, random_scene};
use trgs_core::rng::Rng;
use trgs_core::scene::{Gaussians, PerAttribute, attribute_widths};
use trgs_train::stages::TrainState;

/// `n` Gaussians (SH degree 1, 10% glass) with sizes on both sides of classic densification's
/// clone/split line (1% of a unit extent) and prune line (10%), opacity logits uniform in
/// `opacity` (down to transparent and dead ones), and moments that differ in every word, so that a
/// wrong row or a moment kept where it should restart shows. Returns the generator to draw more.
pub fn random_state(n: usize, seed: u64, opacity: (f64, f64)) -> (TrainState, Rng) {
    let spec = SceneSpec {
        seed,
        gaussians: n,
        planes: 1,
        width: 32,
        height: 24,
        view_angle_deg: 30.0,
        sh_degree: 1,
        glass_fraction: 0.1,
    };
    let mut g: Gaussians<f32> = random_scene(&spec).gaussians.cast();
    let mut rng = Rng::new(seed + 1);
    for i in 0..n {
        let l = rng.range(-7.0, -1.5) as f32;
        g.log_scales[i] = [l, l - 0.3, l - 0.6];
        g.opacity_logits[i] = rng.range(opacity.0, opacity.1) as f32;
    }
    let w = attribute_widths(g.sh_coeffs());
    let moments = |base: f32| {
        PerAttribute::from_fn(|a| {
            (0..n * w[a]).map(|k| base + (a.index() * 100_000 + k) as f32).collect()
        })
    };
    (TrainState { m: moments(0.5), v: moments(-0.25), gaussians: g }, rng)
}
