//! Per-view exposure compensation: each training view's exposure and white balance as an affine
//! colour map (stage `exposure`), learnt with the model by Adam on the CPU from the gradient the
//! GPU sums (twelve numbers a view), as the INRIA code's exposure compensation learns it.
//!
//! The map is what the loss sees, never what a viewer renders: the model stays the scene under
//! one exposure, and a test view's exposure (which training never saw) is fitted on half of its
//! photo at evaluation ([`trgs_core::fit::fit_exposure`], `crate::eval`). A view's map starts at
//! the identity and takes an Adam step each time its view is trained on; its bias correction
//! counts the view's own steps (a view is visited once an epoch, and with the run's step count
//! its first steps would take the full rate at once).
pub mod stage;

use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use trgs_core::pipeline::{AdamRate, AdamSettings, EXPOSURE_IDENTITY, ExposureMatrix};
use trgs_core::reference::adam;

/// The exposures' learning rate: log-linear from `initial` at the run's first step to `last` at
/// its end (the INRIA code's 0.01 and 0.001).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExposureRates {
    pub initial: f64,
    pub last: f64,
}

impl Default for ExposureRates {
    fn default() -> Self {
        Self { initial: 0.01, last: 0.001 }
    }
}

impl ExposureRates {
    /// The rate at `step` of `iterations` (0-based).
    pub fn at(&self, step: u32, iterations: u32) -> f64 {
        let t = (f64::from(step) / f64::from(iterations.max(1))).clamp(0.0, 1.0);
        ((1.0 - t) * self.initial.ln() + t * self.last.ln()).exp()
    }
}

/// One view's exposure and its Adam state (what a checkpoint keeps).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ViewExposure {
    pub matrix: ExposureMatrix,
    pub m: [f64; 12],
    pub v: [f64; 12],
    /// Adam steps this view's exposure has taken.
    pub steps: u32,
}

impl Default for ViewExposure {
    fn default() -> Self {
        Self { matrix: EXPOSURE_IDENTITY, m: [0.0; 12], v: [0.0; 12], steps: 0 }
    }
}

/// The training views' exposures, by view name (a view never trained on has the identity).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ViewExposures {
    views: HashMap<String, ViewExposure>,
}

impl ViewExposures {
    /// The exposure the loss applies to `view`'s render.
    pub fn matrix(&self, view: &str) -> ExposureMatrix {
        self.views.get(view).map_or(EXPOSURE_IDENTITY, |e| e.matrix)
    }

    /// One Adam step of `view`'s exposure with the loss's gradient `grad` at learning rate `lr`,
    /// then every map moved by the same share of that step back, so that their mean stays the
    /// identity. A gradient that is not finite changes nothing (the step's guard has already
    /// refused such a loss).
    ///
    /// The mean is the gauge: a map shared by every view and its inverse in the model's colours
    /// explain the photos equally well. Left free, the maps drift together to make up for what
    /// the model does not yet show (a coarse model's render is darker than every photo: every
    /// offset rises), and the model, rendered as it is, keeps the error. With the mean held at
    /// the identity the common part stays with the model, and a map keeps only its photo's own
    /// difference from the others. A view enters at the identity when first trained on, which
    /// keeps the mean.
    pub fn step(&mut self, view: &str, grad: &ExposureMatrix, lr: f64) {
        if !grad.iter().flatten().all(|g| g.is_finite()) {
            return;
        }
        let e = self.views.entry(view.to_string()).or_default();
        e.steps += 1;
        let before = e.matrix;
        let mut params: Vec<f64> = e.matrix.iter().flatten().copied().collect();
        let grads: Vec<f64> = grad.iter().flatten().copied().collect();
        let rate = AdamRate::uniform(lr);
        adam(&mut params, &grads, &mut e.m, &mut e.v, &rate, e.steps, &AdamSettings::default());
        for (row, chunk) in e.matrix.iter_mut().zip(params.chunks_exact(4)) {
            row.copy_from_slice(chunk);
        }
        let moved = e.matrix;
        let n = self.views.len() as f64;
        for other in self.views.values_mut() {
            for ((v, a), b) in other
                .matrix
                .iter_mut()
                .flatten()
                .zip(moved.iter().flatten())
                .zip(before.iter().flatten())
            {
                *v -= (a - b) / n;
            }
        }
    }

    /// The exposure of every view trained on so far, by name.
    pub fn matrices(&self) -> Vec<(String, ExposureMatrix)> {
        let mut all: Vec<_> = self.views.iter().map(|(k, e)| (k.clone(), e.matrix)).collect();
        all.sort_by(|a, b| a.0.cmp(&b.0));
        all
    }

    /// Whether every number is finite (a checkpoint's state is checked before it is resumed).
    pub fn is_finite(&self) -> bool {
        self.views
            .values()
            .all(|e| e.matrix.iter().flatten().chain(&e.m).chain(&e.v).all(|v| v.is_finite()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rate_falls_log_linearly_from_the_first_to_the_last() {
        let r = ExposureRates::default();
        assert!((r.at(0, 100) - 0.01).abs() < 1e-15);
        assert!((r.at(100, 100) - 0.001).abs() < 1e-15);
        assert!((r.at(50, 100) - (0.01f64 * 0.001).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn a_step_moves_against_the_gradient_and_a_bad_gradient_changes_nothing() {
        let mut e = ViewExposures::default();
        let mut g = [[0.0; 4]; 3];
        g[0][0] = 2.0;
        g[2][3] = -1.0;
        e.step("a", &g, 0.01);
        // One view: its map is the mean, which stays the identity.
        assert_eq!(e.matrix("a"), EXPOSURE_IDENTITY);
        e.step("b", &[[0.0; 4]; 3], 0.01);
        e.step("a", &g, 0.01);
        let (a, b) = (e.matrix("a"), e.matrix("b"));
        // Adam's first step is the rate times the gradient's sign, shared out over two views.
        assert!((a[0][0] - 0.995).abs() < 1e-9 && (a[2][3] - 0.005).abs() < 1e-9, "{a:?}");
        assert!((b[0][0] - 1.005).abs() < 1e-9 && (b[2][3] + 0.005).abs() < 1e-9, "{b:?}");
        assert_eq!(a[1], EXPOSURE_IDENTITY[1]);
        assert_eq!(e.matrix("c"), EXPOSURE_IDENTITY);
        g[1][1] = f64::NAN;
        e.step("a", &g, 0.01);
        assert_eq!(e.matrix("a"), a);
    }

    #[test]
    fn the_mean_of_the_maps_stays_the_identity() {
        let mut e = ViewExposures::default();
        let mut rng = trgs_core::rng::Rng::new(4);
        for k in 0..300 {
            let g: ExposureMatrix =
                std::array::from_fn(|_| std::array::from_fn(|_| rng.range(-1.0, 0.5)));
            e.step(&format!("view {}", k % 7), &g, 0.01);
        }
        let all = e.matrices();
        assert_eq!(all.len(), 7);
        for i in 0..3 {
            for j in 0..4 {
                let mean = all.iter().map(|(_, m)| m[i][j]).sum::<f64>() / 7.0;
                assert!((mean - EXPOSURE_IDENTITY[i][j]).abs() < 1e-12, "{i}{j}: {mean}");
            }
        }
        // The maps did move: the gradients differ from view to view.
        assert!(all.iter().any(|(_, m)| (m[0][3]).abs() > 0.01));
    }
}
