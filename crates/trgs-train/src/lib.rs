//! trgs-train: the optimisation of TR-Gaussians models.
//!
//! - [`run`]: a whole training run ([`run::TrainingRun`]), its settings and its events;
//! - [`trainer`]: one training step on the GPU ([`trainer::Trainer`]);
//! - [`densify`]: how the Gaussian set changes (none, classic, MCMC) behind one interface;
//! - [`gaussian_state`]: the parameters and Adam moments on the GPU, edited together;
//! - [`data`], [`init`], [`plane_init`]: datasets at the training resolution, the initial
//!   Gaussians and the planes fitted from the glass masks; [`reflection_seed`]: the reflected
//!   content stage 1 put behind each plane, mirrored to its front;
//! - [`settings`]: the schedules and rates; [`targets`]: the training photos on the GPU, under
//!   a memory budget; [`checkpoint`]: resumable state on disk;
//! - [`memory`]: the GPU bytes a trainer holds and the process's peak RAM;
//! - [`eval`]: test metrics, renders and comparisons with a synthetic scene's ground truth;
//! - the training stages on the GPU, each with its CPU twin (in `trgs_core::reference`, or beside
//!   the strategy it serves for those that rebuild the set: [`densify::classic`],
//!   [`densify::mcmc`], [`perturb`], [`densify::RowPlan`]): [`adam`], [`losses`],
//!   [`densify_stats`], [`densify_plan`], [`gather_rows`], [`opacity_reset`], [`step_guard`],
//!   [`perturb`] and MCMC's ([`mcmc_relocate`], the others in [`densify::mcmc`]); their kernels
//!   are registered in [`kernels`] and their GPU structs declared in [`layout`].
pub mod adam;
pub mod checkpoint;
pub mod data;
pub mod densify;
pub mod densify_plan;
pub mod densify_stats;
pub mod eval;
pub mod gather_rows;
pub mod gaussian_state;
pub mod init;
pub mod kernels;
pub mod layout;
pub mod losses;
pub mod mcmc_relocate;
pub mod memory;
pub mod opacity_reset;
pub mod perturb;
pub mod plane_adam;
pub mod plane_init;
pub mod reflection_seed;
pub mod run;
pub mod settings;
pub mod step_guard;
pub mod targets;
pub mod trainer;
pub use trgs_core as core;
/// Loading a trained model (in trgs-core, so that the viewer reads models without training code).
pub use trgs_core::io::model;
