//! Image metrics.
