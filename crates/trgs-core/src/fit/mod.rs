//! Fitting: reflection planes for their initialisation (appendix A of the paper;
//! docs/ARCHITECTURE.md, "Plane initialisation"), and a test view's exposure ([`fit_exposure`]).
//!
//! The pipeline: the Gaussians in a band around the annotated glass outline are fitted with
//! [`ransac_plane`] (3-point hypotheses, least-squares refinement), the normal is turned toward
//! the annotated cameras with [`orient_towards`], the inliers are projected into the plane and
//! enclosed by the minimum-area box ([`convex_hull`], each hull edge tried in [`min_area_box`]);
//! [`fit_rectangle`] does all but the orientation. [`refine_to_masks`] then moves the rectangle
//! from the pane's frame onto the glass the masks outline, and [`sample_rectangle`] places the
//! glass Gaussians uniformly on it.
mod exposure;
mod hull;
mod openings;
mod planarity;
mod propose;
mod ransac;
mod rectangle;
mod reflector_parts;
mod see_through;
mod silhouette;
mod structures;

pub use exposure::fit_exposure;
pub use hull::{OrientedBox, convex_hull, min_area_box};
pub use propose::{PlaneCandidate, Proposal, ProposalSettings, depth_scale, propose_planes};
pub use ransac::{PlaneFit, orient_towards, ransac_plane, symmetric_eigen};
pub use rectangle::{RectangleFit, fit_rectangle, sample_rectangle};
pub use see_through::{SeeThrough, see_through};
pub use silhouette::{SilhouetteFit, SilhouetteSettings, refine_to_masks};
pub use structures::{Structure, StructureSettings, find_structures, inside_convex};
