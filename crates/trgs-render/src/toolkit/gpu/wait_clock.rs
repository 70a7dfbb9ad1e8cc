//! The time a wait for the GPU counts against its limit ([`super::wait_for_submission`]): the
//! time the process ran, not the time on the clock.
use std::time::Duration;

/// The longest single wait of [`super::wait_for_submission`]: short against the wait limit, so
/// that a pause of the process (job control's Ctrl-Z or SIGSTOP, a machine put to sleep) costs at
/// most this much of it; long against the cost of a poll.
pub const WAIT_SLICE: Duration = Duration::from_secs(1);

/// The slices a wait has counted against its limit. A slice that runs out counts for its length,
/// however long it took on the clock: longer means the process did not run for part of it. (A
/// driver that gave up early would make the wait end sooner, never loop without end.)
#[derive(Clone, Copy, Debug)]
pub(super) struct WaitClock {
    limit: Duration,
    counted: Duration,
}

impl WaitClock {
    pub(super) fn new(limit: Duration) -> Self {
        Self { limit, counted: Duration::ZERO }
    }

    /// The next slice to wait for, None once the limit is reached.
    pub(super) fn next_slice(&self) -> Option<Duration> {
        let left = self.limit.saturating_sub(self.counted);
        (!left.is_zero()).then(|| left.min(WAIT_SLICE))
    }

    /// `slice` ran out without the work finishing.
    pub(super) fn add(&mut self, slice: Duration) {
        self.counted += slice;
    }
}

#[cfg(test)]
mod tests {
    use super::{WAIT_SLICE, WaitClock};
    use std::time::Duration;

    #[test]
    fn a_wait_that_never_ends_stops_at_the_limit_slice_by_slice() {
        let mut clock = WaitClock::new(Duration::from_millis(2500));
        let mut slices = Vec::new();
        while let Some(slice) = clock.next_slice() {
            slices.push(slice.as_millis());
            clock.add(slice);
        }
        assert_eq!(slices, [1000, 1000, 500]);
        assert_eq!(WAIT_SLICE, Duration::from_secs(1));
    }

    #[test]
    fn no_limit_no_wait() {
        assert_eq!(WaitClock::new(Duration::ZERO).next_slice(), None);
    }
}
