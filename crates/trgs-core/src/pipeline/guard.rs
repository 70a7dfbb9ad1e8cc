//! The bits of the step guard's word: stage `step_guard` sets them from `emit_keys`' flag and the
//! loss sums, the updates change nothing while any is set, and the trainer reads which one
//! stopped a step.

/// The guard's bit: the frame's key list dropped keys.
pub const GUARD_KEYS_DROPPED: u32 = 1;
/// The guard's bit: a strip sum of the loss is not finite.
pub const GUARD_LOSS_NOT_FINITE: u32 = 2;
