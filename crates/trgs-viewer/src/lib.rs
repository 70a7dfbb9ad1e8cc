//! trgs viewer (egui). The app arrives with the viewer issue; it renders through `trgs-render`.
pub use trgs_core as core;
