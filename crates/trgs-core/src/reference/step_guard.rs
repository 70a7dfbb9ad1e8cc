//! Stage `step_guard`: whether a training step may change the model, decided where its inputs
//! are (on the GPU) so that the step need not wait for them: not when its frame's key list
//! dropped keys (the frame, and so every gradient, is wrong), nor when a sum of its loss is not
//! finite. The updates of the step (`adam`, `mcmc_noise`, `densify_stats`) leave everything as
//! it was when the guard is set, and the trainer learns why when the guard comes back.

use crate::pipeline::{GUARD_KEYS_DROPPED, GUARD_LOSS_NOT_FINITE};

/// The guard word of a step: `keys_dropped` is `emit_keys`' flag (nonzero when the list dropped
/// keys), `sums` the strips' sums of `loss_sums`.
pub fn step_guard(keys_dropped: u32, sums: &[[f32; 4]]) -> u32 {
    let dropped = if keys_dropped != 0 { GUARD_KEYS_DROPPED } else { 0 };
    let not_finite = sums.iter().flatten().any(|v| !v.is_finite());
    dropped | if not_finite { GUARD_LOSS_NOT_FINITE } else { 0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_cause_sets_its_bit() {
        let fine = [[1.0, 2.0, 3.0, 0.0], [0.0; 4]];
        assert_eq!(step_guard(0, &fine), 0);
        assert_eq!(step_guard(1, &fine), GUARD_KEYS_DROPPED);
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            let sums = [[1.0, 2.0, 3.0, 0.0], [0.0, 0.0, 0.0, bad]];
            assert_eq!(step_guard(0, &sums), GUARD_LOSS_NOT_FINITE);
            assert_eq!(step_guard(7, &sums), GUARD_KEYS_DROPPED | GUARD_LOSS_NOT_FINITE);
        }
    }
}
