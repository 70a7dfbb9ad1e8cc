//! Plane fitting for initialising reflection planes (appendix A of the paper;
//! docs/ARCHITECTURE.md, "Plane initialisation").
//!
//! The pipeline: the Gaussians in a band around the annotated glass outline are fitted with
//! [`ransac_plane`] (3-point hypotheses, least-squares refinement), the normal is turned toward
//! the annotated cameras with [`orient_towards`], the inliers are projected into the plane and
//! enclosed by the minimum-area box ([`convex_hull`] + rotating calipers in [`min_area_box`]);
//! [`fit_rectangle`] does all but the orientation. [`sample_rectangle`] then places the glass
//! Gaussians uniformly on the rectangle.
mod hull;
mod ransac;
mod rectangle;

pub use hull::{OrientedBox, convex_hull, min_area_box};
pub use ransac::{PlaneFit, orient_towards, ransac_plane, symmetric_eigen};
pub use rectangle::{RectangleFit, fit_rectangle, sample_rectangle};
