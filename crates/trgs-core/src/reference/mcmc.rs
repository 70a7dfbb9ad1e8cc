//! Stages `mcmc_regularise` and `mcmc_noise` of MCMC densification (3DGS-MCMC, Kheradmand et
//! al. 2024), in f64; the GPU stages (shaders/training/mcmc_regularise.wgsl and
//! shaders/training/mcmc_noise.wgsl) run the same arithmetic in f32 with the same random numbers.
//!
//! - `mcmc_regularise` adds the gradient of the paper's regularisers to the Gaussians' gradients:
//!   `lambda_o mean(o) + lambda_s mean(s)` over the primary Gaussians' opacities `o` and scale
//!   components `s` (sums divided by the scene's N and 3N; glass Gaussians add nothing), which pushes unused Gaussians to
//!   transparency so that relocation can reuse them.
//! - `mcmc_noise` is the SGLD exploration term added to every primary mean after the optimiser
//!   step: `Sigma eta * sigmoid(k (1 - o - t)) * scale`, with `Sigma` the Gaussian's 3D
//!   covariance, `eta` standard normal, `k = 100`, `t = 0.995` (noise mostly for nearly
//!   transparent Gaussians) and `scale` the position learning rate times the noise rate.
//!
//! Glass Gaussians lie on their plane and take part in neither.
use super::project::{covariance3d, sigmoid};
use crate::pipeline::{MAX_REGULARISED_LOG_SCALE, NOISE_GATE_STEEPNESS, NOISE_GATE_THRESHOLD};
use crate::scene::{Gaussians, Population};
use glam::DVec3;

/// PCG hash (Jarzynski and Olano 2020), on u32 exactly as in WGSL.
pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// Draw `j`'s uniform integer below `total` (> 0) at `seed`: the high word of a 32-bit hash
/// times `total` (as WGSL's `draw_below`, which builds the 64-bit product from 16-bit halves).
pub fn draw_below(seed: u32, j: u32, total: u32) -> u32 {
    let r = pcg_hash(j ^ pcg_hash(seed));
    ((u64::from(r) * u64::from(total)) >> 32) as u32
}

/// The standard normal number of component `c` of Gaussian `i` at `seed` (Box-Muller on two
/// 24-bit uniforms, which f32 holds exactly).
pub fn noise_normal(seed: u32, i: u32, c: u32) -> f64 {
    let h1 = pcg_hash(i.wrapping_mul(3).wrapping_add(c) ^ pcg_hash(seed));
    let h2 = pcg_hash(h1);
    let u1 = f64::from((h1 >> 8) + 1) / 16_777_216.0;
    let u2 = f64::from(h2 >> 8) / 16_777_216.0;
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// The offset `mcmc_noise` adds to the mean of Gaussian `i` (zero for a glass Gaussian).
pub fn noise_offset(g: &Gaussians<f64>, i: usize, scale: f64, seed: u32) -> DVec3 {
    if g.populations[i] == Population::Glass {
        return DVec3::ZERO;
    }
    let o = sigmoid(g.opacity_logits[i]);
    let gate = sigmoid(NOISE_GATE_STEEPNESS * (1.0 - o - NOISE_GATE_THRESHOLD));
    let eta = DVec3::new(
        noise_normal(seed, i as u32, 0),
        noise_normal(seed, i as u32, 1),
        noise_normal(seed, i as u32, 2),
    );
    covariance3d(g, i) * eta * (gate * scale)
}

/// Stage `mcmc_noise`: add the exploration noise to every mean.
pub fn mcmc_noise(g: &mut Gaussians<f64>, scale: f64, seed: u32) {
    for i in 0..g.len() {
        let d = noise_offset(g, i, scale, seed);
        for (m, v) in g.means[i].iter_mut().zip(d.to_array()) {
            *m += v;
        }
    }
}

/// Stage `mcmc_regularise`: add dL/d(opacity logit) and dL/d(log scale) of the regularisers to
/// `grad_opacity_logits` and `grad_log_scales`. `count` is the N of the means (the scene's size).
pub fn mcmc_regularise(
    g: &Gaussians<f64>,
    opacity_weight: f64,
    scale_weight: f64,
    count: usize,
    grad_opacity_logits: &mut [f64],
    grad_log_scales: &mut [[f64; 3]],
) {
    let n = count.max(1) as f64;
    for i in 0..g.len() {
        if g.populations[i] == Population::Glass {
            continue;
        }
        let o = sigmoid(g.opacity_logits[i]);
        grad_opacity_logits[i] += opacity_weight / n * o * (1.0 - o);
        for (gs, ls) in grad_log_scales[i].iter_mut().zip(g.log_scales[i]) {
            *gs += scale_weight / (3.0 * n) * ls.min(MAX_REGULARISED_LOG_SCALE).exp();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normals_have_unit_moments() {
        let n = 30_000;
        let xs: Vec<f64> = (0..n).map(|i| noise_normal(42, i, i % 3)).collect();
        let mean = xs.iter().sum::<f64>() / f64::from(n);
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / f64::from(n);
        assert!(mean.abs() < 0.02, "mean {mean}");
        assert!((var - 1.0).abs() < 0.03, "variance {var}");
        assert!(xs.iter().all(|x| x.is_finite()));
        assert_ne!(noise_normal(1, 5, 0), noise_normal(2, 5, 0), "the seed must matter");
    }

    #[test]
    fn noise_gate_spares_opaque_gaussians() {
        let mut g = Gaussians::<f64>::zeros(2, 0);
        g.rotations = vec![[1.0, 0.0, 0.0, 0.0]; 2];
        g.log_scales = vec![[0.0; 3]; 2];
        g.opacity_logits = vec![4.0, -8.0];
        let opaque = noise_offset(&g, 0, 1.0, 3).length();
        let transparent = noise_offset(&g, 1, 1.0, 3).length();
        assert!(opaque < 1e-6 * transparent, "{opaque} vs {transparent}");
        g.populations[1] = Population::Glass;
        assert_eq!(noise_offset(&g, 1, 1.0, 3), DVec3::ZERO);
    }

    /// The regulariser gradients are those of lambda_o mean(o) + lambda_s mean(s), by central
    /// differences.
    #[test]
    fn regulariser_gradients_match_finite_differences() {
        let mut g = Gaussians::<f64>::zeros(3, 0);
        g.opacity_logits = vec![0.3, -1.2, 2.0];
        g.log_scales = vec![[-1.0, 0.2, -3.0], [0.5, -0.5, 0.0], [-2.0, -2.0, 1.0]];
        g.populations[2] = Population::Glass;
        let (wo, ws) = (0.01, 0.02);
        let loss = |g: &Gaussians<f64>| {
            let primary: Vec<usize> =
                (0..g.len()).filter(|&i| g.populations[i] == Population::Primary).collect();
            let n = g.len() as f64;
            let o: f64 = primary.iter().map(|&i| sigmoid(g.opacity_logits[i])).sum();
            let s: f64 = primary.iter().flat_map(|&i| g.log_scales[i].map(f64::exp)).sum();
            wo * o / n + ws * s / (3.0 * n)
        };
        let mut go = vec![0.0; 3];
        let mut gs = vec![[0.0; 3]; 3];
        mcmc_regularise(&g, wo, ws, g.len(), &mut go, &mut gs);
        let h = 1e-6;
        for i in 0..3 {
            let mut p = g.clone();
            p.opacity_logits[i] += h;
            let mut m = g.clone();
            m.opacity_logits[i] -= h;
            let fd = (loss(&p) - loss(&m)) / (2.0 * h);
            assert!((fd - go[i]).abs() < 1e-9, "opacity {i}: {fd} vs {}", go[i]);
            for c in 0..3 {
                let mut p = g.clone();
                p.log_scales[i][c] += h;
                let mut m = g.clone();
                m.log_scales[i][c] -= h;
                let fd = (loss(&p) - loss(&m)) / (2.0 * h);
                assert!((fd - gs[i][c]).abs() < 1e-9, "scale {i},{c}: {fd} vs {}", gs[i][c]);
            }
        }
    }
}
