//! The training stages on the GPU, for the stage tests, the benchmarks and apps that compose a
//! step of their own. Each is one WGSL file under shaders/training/ (or one family of them) and
//! one Rust type of the same name, with its CPU twin in `trgs_core::reference` or, for the stages
//! that rebuild the Gaussian set, beside its strategy ([`crate::densify`]). Their kernels are
//! registered in [`TRAINING_KERNELS`] and their GPU structs declared once in [`layout`].
pub use crate::densify::classic::{
    DensifyPlanOutput, GpuDensifyPlan, GpuDensifyStats, GpuOpacityReset, opacity_reset_cap,
    opacity_reset_logits,
};
pub use crate::densify::mcmc::{GpuMcmcRelocate, McmcKernels, McmcRelocateOutput};
pub use crate::exposure::stage::{ExposureKernels, PendingExposureGrad};
pub use crate::exposure::{ExposureRates, ViewExposure, ViewExposures};
pub use crate::gaussians::adam::{Adam, AdamMoments};
pub use crate::gaussians::gather_rows::{GatherSources, GpuRowGather};
pub use crate::gaussians::plan::{Geometry, RowPlan, TrainState};
pub use crate::gaussians::state::GaussianState;
pub use crate::kernels::TRAINING_KERNELS;
pub use crate::losses::step_guard;
pub use crate::losses::{
    ChannelPasses, GpuTarget, LossError, LossKernels, LossLayers, LossSettings, LossValues,
    PendingLoss, check_frame_size,
};
pub use crate::planes::perturb;
pub use crate::trainer::targets;

/// The training stages' GPU structs and the WGSL prelude generated from them.
pub mod layout {
    pub use crate::layout::*;
}
