//! The offset along its normal at which the refit of a kept plane (`super::plane_refit`)
//! places glass seen through: the median of the trial's, the glass's outline's and the
//! proposal's.
use glam::DVec3;
use trgs_core::Image;
use trgs_core::fit::{SilhouetteSettings, refine_to_masks};
use trgs_core::scene::{Camera, ReflectionPlane};

/// The offsets along a refit's normal, from its start's centre, that [`offset_along_normal`]
/// weighs, and the one it took.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct OffsetChoice {
    /// Where the glass's outline puts the plane when the refit may move it along its normal.
    pub outline: Option<f64>,
    /// Where the proposal's structure is.
    pub proposal: Option<f64>,
    pub taken: f64,
}

impl OffsetChoice {
    /// The trial's own offset, kept.
    pub fn trial() -> Self {
        Self { outline: None, proposal: None, taken: 0.0 }
    }

    pub fn describe(&self) -> String {
        match (self.outline, self.proposal) {
            (Some(o), Some(p)) => format!(
                "offset {:+.3} from the trial's (its outline alone {o:+.3}, its proposal {p:+.3})",
                self.taken
            ),
            _ => "offset the trial's".to_string(),
        }
    }
}

/// The offset along `start`'s normal (from its centre, which the trial trained) at which the
/// refit places glass seen through: the median of three estimates, each of which fails alone
/// where the other two hold, and whose failures lie on opposite sides of the glass.
/// - The trial's own (0): the reflection pins it, but poorly where the photos see the
///   reflected space from one line (on walk-by the trial moved its plane from 1.0 to 5.7 cm
///   in front of the glass).
/// - The outline's, `views` fitted free to move along the normal: the outline of what is seen
///   through a pane is its opening's, not its glass's. The sides of the opening behind the
///   glass narrow it on one side as those in front hide the glass on the other, so the fit
///   settles between the opening's two ends, behind the glass where the glass sits in front
///   of the opening's middle (2.8-5.4 cm behind on the scene family's members).
/// - The proposal's structure: the face of the frame or of the wall around the glass, a few
///   centimetres in front of it, or the glass itself.
///
/// docs/RESULTS.md ("Planes without masks") has the three on each member. `proposal` is a point
/// of the proposal's plane; without it, or without an outline fit, the trial's.
pub(super) fn offset_along_normal(
    start: &ReflectionPlane,
    views: &[(&Camera, &Image<u8>)],
    proposal: Option<DVec3>,
) -> OffsetChoice {
    let n = start.unit_normal();
    let free = refine_to_masks(start, views, 1, &SilhouetteSettings::default());
    let outline = free.map(|f| (f.plane.centre - start.centre).dot(n));
    let proposal = proposal.map(|p| (p - start.centre).dot(n));
    match (outline, proposal) {
        (Some(o), Some(p)) => {
            OffsetChoice { outline, proposal, taken: 0f64.clamp(o.min(p), o.max(p)) }
        }
        _ => OffsetChoice::trial(),
    }
}
