//! The constants of MCMC densification's `mcmc_regularise` and `mcmc_noise` stages, which the
//! GPU stages and their twins (`reference::mcmc_*`) apply alike.

/// Steepness and threshold of the noise gate on `1 - opacity` (the paper's k and t).
pub const NOISE_GATE_STEEPNESS: f64 = 100.0;
pub const NOISE_GATE_THRESHOLD: f64 = 0.995;

/// The scale regulariser's gradient is exp(log-scale): above this log-scale (a scale of 2.4e17)
/// it stops growing, so that one diverged Gaussian gets a large finite gradient (at most 8e14
/// times the weight) whose square, Adam's second moment, is still finite in f32 (below 1.8e19
/// is needed): Adam turns it into a bounded step. Uncapped, the gradient is infinite in f32 and
/// Adam's step NaN; capped at 80, the square overflows and the coordinate freezes for good.
pub const MAX_REGULARISED_LOG_SCALE: f64 = 40.0;
