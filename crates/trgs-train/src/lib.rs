//! trgs-train: the optimisation of TR-Gaussians models.
//!
//! An app trains with [`TrainingRun`]: [`TrainingRun::start`] a [`RunConfig`] (or
//! [`TrainingRun::resume`] a run folder), each with [`RunOptions`] (a progress sink for the
//! photos' loading, a GPU context, what the machine sets anew), then read its [`RunEvent`]s.
//! Below the run, a [`Trainer`] takes one training step on the GPU with [`TrainSettings`];
//! [`TrainingData`] is a scene folder at the training [`Resolution`].
//!
//! Modules an app may need beyond these:
//! - [`run`]: the run's settings record (`train`'s arguments), demo scenes, its files;
//! - [`checkpoint`]: resumable state on disk;
//! - [`eval`]: test metrics, renders and comparisons with a synthetic scene's ground truth;
//! - [`densify`]: the densification strategies (none, classic, MCMC) and the CPU twins of
//!   their decisions;
//! - [`stages`]: the training stages on the GPU, each with its CPU twin, for tests,
//!   benchmarks and apps that compose a step of their own.
//!
//! Inside, one folder per concern (docs/ARCHITECTURE.md, "trgs-train"): `run/` (a whole run),
//! `trainer/` (one step), `gaussians/` (the set and its Adam moments), `densify/` (strategies,
//! each with its GPU stages), `planes/` (initialisation, seeds, plane Adam, perturbation),
//! `losses/`, `exposure/` (per-view exposure compensation), `data/`; `kernels` and `layout` hold
//! the crate's kernel table and GPU structs.
pub mod bake;
mod data;
pub mod densify;
pub mod eval;
mod exposure;
mod gaussians;
mod kernels;
mod layout;
mod losses;
mod planes;
pub mod run;
mod settings;
pub mod stages;
mod trainer;

pub use data::{
    LoadOptions, LoadProgress, Resolution, TrainingData, View, load_masked_views, resize_area_u8,
};
pub use densify::{ClassicSettings, Densification, DensifyEvent, McmcSettings};
pub use eval::Evaluation;
pub use gaussians::init::{InitialShape, SeedPoint, gaussians_from_points};
pub use planes::init::{PlaneInitSettings, initialise_planes};
pub use run::checkpoint;
pub use run::{RunConfig, RunEvent, RunOptions, RunSummary, StepEvent, TrainingRun};
pub use settings::{Stage, TrainSettings};
pub use trainer::memory::{GpuMemory, human_bytes};
pub use trainer::{StepStats, StepTimes, Trainer};
pub use trgs_core as core;
/// Loading a trained model (in trgs-core, so that the viewer reads models without training code).
pub use trgs_core::io::model;
