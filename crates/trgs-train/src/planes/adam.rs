//! Adam on a reflection plane's parameters: its offset along the normal, its normal and its R0
//! logit (on the CPU: a few numbers a plane).
//!
//! The centre is not stepped per coordinate. Its true gradient lies along the normal (the mirror
//! `x - 2 ((x - u).n) n` sees the centre u only through u.n), and per-coordinate Adam divides
//! each world coordinate of that gradient by its own running magnitude: a normal along z with a
//! small tilt would take full-size steps in x and y too, and the centre would wander across the
//! plane, dragging the plane's rectangle (its hit region) off the window. Adam therefore steps
//! the scalar offset `d = u.n` and moves the centre along the normal only; the rectangle stays
//! where the initialisation fitted it.
//!
//! Where the glass masks pin the plane, its offset is also kept within an [`OffsetLimit`] of
//! where they put it.
use crate::run::checkpoint::PlaneMoments;
use glam::DVec3;
use serde::{Deserialize, Serialize};
use trgs_core::pipeline::{AdamRate, AdamSettings};
use trgs_core::plane_grad::PlaneGrad;
use trgs_core::reference::adam;
use trgs_core::scene::ReflectionPlane;

/// Learning rates of one plane step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneRates {
    /// Of the offset along the normal (world units).
    pub offset: f64,
    pub normal: f64,
    pub r0_logit: f64,
}

/// Bounds on a plane's offset along its normal: within `tolerance` of `anchor`. Set where the
/// glass masks pin the plane ([`trgs_core::fit::refine_to_masks`]), to as far as the plane can
/// move before its outline moves a pixel in an annotated view. The photos alone pin the offset
/// poorly where the plane reflects a space no camera sees: a step along the normal moves every
/// reflection by twice as much, and the Gaussians there can follow it at no cost, so without the
/// bound the plane drifts off the glass over a run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OffsetLimit {
    pub anchor: [f64; 3],
    pub tolerance: f64,
}

impl OffsetLimit {
    /// A finite anchor and a finite tolerance of at least 0 (what `apply` needs).
    pub fn is_valid(&self) -> bool {
        self.anchor.iter().all(|v| v.is_finite())
            && self.tolerance.is_finite()
            && self.tolerance >= 0.0
    }

    /// `plane` moved along its normal back within the bounds, when it has left them.
    fn apply(&self, plane: &mut ReflectionPlane) {
        let n = plane.unit_normal();
        let off = (plane.centre - DVec3::from_array(self.anchor)).dot(n);
        let kept = off.clamp(-self.tolerance, self.tolerance);
        plane.centre += (kept - off) * n;
    }
}

/// One Adam step (step number `t`, from 1) of `plane` with gradient `g`. Moment slot 0 holds the
/// offset's, 3..6 the normal's and 6 the R0 logit's; slots 1 and 2 stay unused. The offset then
/// stays within the plane's [`OffsetLimit`], if it has one.
pub fn plane_adam(
    plane: &mut ReflectionPlane,
    g: &PlaneGrad,
    mom: &mut PlaneMoments,
    rates: &PlaneRates,
    t: u32,
) {
    let limit = mom.offset_limit;
    // Adam on the moment slots `slots` with rate `lr`.
    let mut step = |values: &mut [f64], grads: &[f64], slots: std::ops::Range<usize>, lr: f64| {
        let (m, v) = (&mut mom.m[slots.clone()], &mut mom.v[slots]);
        adam(values, grads, m, v, &AdamRate::uniform(lr), t, &AdamSettings::default());
    };
    let n = plane.unit_normal();
    let mut offset = [plane.centre.dot(n)];
    step(&mut offset, &[g.centre.dot(n)], 0..1, rates.offset);
    plane.centre += (offset[0] - plane.centre.dot(n)) * n;
    if let Some(limit) = &limit {
        limit.apply(plane);
    }
    let mut normal = plane.normal.to_array();
    step(&mut normal, &g.normal.to_array(), 3..6, rates.normal);
    plane.normal = DVec3::from_array(normal);
    let mut r0 = [plane.r0_logit];
    step(&mut r0, &[g.r0_logit], 6..7, rates.r0_logit);
    plane.r0_logit = r0[0];
    plane.orthogonalise_axis();
}

#[cfg(test)]
mod tests {
    use super::*;
    use trgs_core::scene::Material;

    fn tilted_plane() -> ReflectionPlane {
        let normal = DVec3::new(-0.08, 0.09, -0.99).normalize();
        ReflectionPlane::new(
            DVec3::new(1.1, -1.5, 1.8),
            normal,
            DVec3::X,
            1.6,
            1.0,
            Material::Glass,
        )
    }

    /// A centre gradient along a tilted normal, as the mirror gives, moves the centre along the
    /// normal only, in the descent direction; an in-plane gradient does not move it at all.
    #[test]
    fn the_centre_moves_along_the_normal_only() {
        let rates = PlaneRates { offset: 1e-2, normal: 0.0, r0_logit: 0.0 };
        let mut plane = tilted_plane();
        let start = plane.centre;
        let n = plane.unit_normal();
        let mut mom = PlaneMoments::default();
        for t in 1..=50 {
            let g = PlaneGrad { centre: 0.3 * n, normal: DVec3::ZERO, r0_logit: 0.0 };
            plane_adam(&mut plane, &g, &mut mom, &rates, t);
        }
        let moved = plane.centre - start;
        let along = moved.dot(n);
        assert!(along < -0.4, "descends along the normal: {along}");
        assert!((moved - along * n).length() < 1e-12, "in-plane drift {:?}", moved - along * n);

        let mut plane = tilted_plane();
        let mut mom = PlaneMoments::default();
        let in_plane = n.cross(DVec3::X).normalize();
        for t in 1..=50 {
            let g = PlaneGrad { centre: in_plane, normal: DVec3::ZERO, r0_logit: 0.0 };
            plane_adam(&mut plane, &g, &mut mom, &rates, t);
        }
        assert!((plane.centre - start).length() < 1e-12, "{:?}", plane.centre - start);
    }

    /// A steady push along the normal moves the plane to its offset limit and no further, and
    /// the limit holds on the side the push comes from as well.
    #[test]
    fn the_offset_stays_within_its_limit() {
        let rates = PlaneRates { offset: 1e-2, normal: 0.0, r0_logit: 0.0 };
        for push in [0.3, -0.3] {
            let mut plane = tilted_plane();
            let start = plane.centre;
            let n = plane.unit_normal();
            let limit = OffsetLimit { anchor: start.to_array(), tolerance: 0.05 };
            let mut mom = PlaneMoments { offset_limit: Some(limit), ..PlaneMoments::default() };
            for t in 1..=50 {
                let g = PlaneGrad { centre: push * n, normal: DVec3::ZERO, r0_logit: 0.0 };
                plane_adam(&mut plane, &g, &mut mom, &rates, t);
            }
            let along = (plane.centre - start).dot(n);
            assert!((along.abs() - 0.05).abs() < 1e-12, "{along}");
            assert!(along * push < 0.0, "moved against the push: {along}");
        }
    }
}
