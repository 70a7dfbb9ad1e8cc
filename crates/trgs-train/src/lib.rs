//! trgs training. The optimiser arrives with the training issue.
pub use trgs_core as core;
