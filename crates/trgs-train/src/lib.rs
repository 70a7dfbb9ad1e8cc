//! trgs-train: optimisation of TR-Gaussians models, and the command-line tools around it (`train`,
//! `render`, `bench`): datasets at the training resolution ([`data`]), the initial Gaussians
//! ([`init`]), the settings and schedules ([`settings`]), the GPU Adam step ([`adam`]), the
//! losses and regularisers on the GPU ([`losses`]), densification ([`densify`]), plane initialisation
//! ([`plane_init`]), the training step ([`trainer`]) and checkpoints ([`checkpoint`]).
pub mod adam;
pub mod checkpoint;
pub mod data;
pub mod densify;
pub mod densify_stats;
pub mod eval;
pub mod gather_rows;
pub mod gaussian_state;
pub mod init;
pub mod losses;
/// Loading a trained model (moved to trgs-core so that the viewer reads models without training code).
pub use trgs_core::io::model;
pub mod perturb;
pub mod plane_adam;
pub mod plane_init;
pub mod settings;
pub mod trainer;
pub use trgs_core as core;
