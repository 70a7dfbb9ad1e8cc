//! How the Gaussian set changes during training. A run chooses one [`Densification`] (none,
//! classic 3DGS, or 3DGS-MCMC); the trainer drives it through one interface,
//! [`DensifyStrategy`], whose hooks it calls at fixed points of every step. Strategies decide;
//! they edit the Gaussians only through [`GaussianState`](crate::stages::GaussianState)'s shared operations, which change the
//! parameters and their Adam moments together.
pub mod classic;
pub mod mcmc;
pub mod strategy;

pub use classic::{ClassicDensification, ClassicSettings, DensifyReport, DensifyStats};
pub use mcmc::{McmcDensification, McmcReport, McmcSettings};
pub use strategy::DensifyEvent;
pub use strategy::{DensifyStrategy, NoDensification, StepView};

use crate::gaussians::init::InitialShape;
use trgs_render::GpuContext;

/// The densification a run uses, with its settings: the value a run is configured with.
#[derive(Clone, Debug, PartialEq)]
pub enum Densification {
    /// The Gaussian count stays as initialised.
    None,
    /// 3DGS's clone, split, prune and opacity reset ([`classic`]).
    Classic(ClassicSettings),
    /// 3DGS-MCMC's relocation, growth to a cap, noise and regularisers ([`mcmc`]).
    Mcmc(McmcSettings),
}

impl Densification {
    /// The strategy for a set of `n` Gaussians, continuing from `stats` (a checkpoint's
    /// classic statistics) when given.
    pub fn strategy(
        &self,
        ctx: &GpuContext,
        n: usize,
        stats: Option<&DensifyStats>,
    ) -> Box<dyn DensifyStrategy> {
        match self {
            Self::None => Box::new(NoDensification),
            Self::Classic(s) => Box::new(ClassicDensification::resumed(ctx, s.clone(), n, stats)),
            Self::Mcmc(s) => Box::new(McmcDensification::new(ctx, s.clone())),
        }
    }

    /// How the initial Gaussians are shaped for this densification.
    pub fn initial_shape(&self) -> InitialShape {
        match self {
            Self::Mcmc(_) => InitialShape::MCMC,
            Self::None | Self::Classic(_) => InitialShape::CLASSIC,
        }
    }
}
