//! The Gaussian set being trained: its parameters and their Adam moments on the GPU, edited
//! together ([`state::GaussianState`]); the same on the CPU ([`plan::TrainState`]) with the
//! row plans that densification and relocation make ([`plan::RowPlan`]) and the stage that
//! carries them out on the GPU ([`gather_rows`]); the Adam stage ([`adam`]); and the initial
//! set made from seed points ([`init`]).
pub mod adam;
pub mod gather_rows;
pub mod init;
pub mod plan;
pub mod state;
