//! A frame's geometry stages read back in the CPU twin's form (for stage-by-stage tests): what
//! [`crate::toolkit::FrameStages`] returns; `stage_reads` reads them.
use crate::layout::ProjectedGaussian;

/// Intermediate results of one view's geometry stages (for stage-by-stage tests).
#[derive(Clone, Debug)]
pub struct ViewIntermediates {
    pub projected: Vec<ProjectedGaussian>,
    /// Tile counts per Gaussian.
    pub counts: Vec<u32>,
    /// This view's Gaussians in the frame's depth order.
    pub order: Vec<u32>,
    /// This view's keys (tile indices of the whole grid) and values as emitted, in emission
    /// order (with `capture_intermediates`).
    pub emitted: Option<(Vec<u32>, Vec<u32>)>,
    /// This view's sorted keys (tile indices of the whole grid) and values.
    pub sorted_keys: Vec<u32>,
    pub sorted_values: Vec<u32>,
    pub ranges: Vec<(u32, u32)>,
}

/// The frame's depth order, read back (for stage-by-stage tests).
#[derive(Clone, Debug)]
pub struct DepthOrderIntermediates {
    /// Entry indices (`view * Gaussians + index`), front to back.
    pub entries: Vec<u32>,
    /// Their depth bits.
    pub depths: Vec<u32>,
    /// The exclusive scan of their tile counts.
    pub offsets: Vec<u32>,
    /// Keys of all views.
    pub total: u32,
}
