//! Plane overlays: each plane's rectangle and normal as 2D line segments in image pixels, clipped
//! against the near plane in camera space first, so that a plane passing beside or behind the
//! camera draws only its visible part.
use glam::{DVec2, DVec3};
use trgs_core::scene::{Camera, ReflectionPlane};

/// Camera-space depth below which a segment is cut.
const NEAR: f64 = 1e-3;

/// The visible part of the world segment a-b, in pixels.
pub fn project_segment(camera: &Camera, a: DVec3, b: DVec3) -> Option<Segment> {
    let (mut ca, mut cb) = (camera.pose.transform_point(a), camera.pose.transform_point(b));
    if ca.z < NEAR && cb.z < NEAR {
        return None;
    }
    // Cut at z = NEAR on the side that is behind.
    let cut = |p: DVec3, q: DVec3| p + (q - p) * ((NEAR - p.z) / (q.z - p.z));
    if ca.z < NEAR {
        ca = cut(ca, cb);
    } else if cb.z < NEAR {
        cb = cut(cb, ca);
    }
    let k = &camera.intrinsics;
    let px = |c: DVec3| DVec2::new(k.fx * c.x / c.z + k.cx, k.fy * c.y / c.z + k.cy);
    let (pa, pb) = (px(ca), px(cb));
    (pa.is_finite() && pb.is_finite()).then_some((pa, pb))
}

/// A line segment in pixels.
pub type Segment = (DVec2, DVec2);

/// A plane's overlay in pixels: the visible parts of its rectangle's edges, and of its normal
/// (from the centre, a quarter of the shorter side long).
#[derive(Clone, Debug, Default)]
pub struct PlaneOverlay {
    pub edges: Vec<Segment>,
    pub normal: Option<Segment>,
}

pub fn plane_overlay(camera: &Camera, plane: &ReflectionPlane) -> PlaneOverlay {
    let c = plane.corners();
    let edges = (0..4).filter_map(|i| project_segment(camera, c[i], c[(i + 1) % 4])).collect();
    let tip = plane.centre + plane.unit_normal() * 0.25 * plane.width.min(plane.height);
    PlaneOverlay { edges, normal: project_segment(camera, plane.centre, tip) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use trgs_core::scene::{Intrinsics, Pose};

    fn camera() -> Camera {
        let k = Intrinsics::from_fov_x(1.0, 100, 80);
        Camera::new("c", k, Pose::default())
    }

    #[test]
    fn a_point_ahead_lands_where_the_pinhole_puts_it() {
        let cam = camera();
        let (a, b) = project_segment(&cam, DVec3::new(0.0, 0.0, 2.0), DVec3::new(1.0, 0.5, 2.0))
            .expect("in front");
        assert!((a - DVec2::new(50.0, 40.0)).length() < 1e-9);
        let k = cam.intrinsics;
        assert!((b - DVec2::new(50.0 + k.fx * 0.5, 40.0 + k.fy * 0.25)).length() < 1e-9);
    }

    #[test]
    fn segments_behind_are_dropped_and_crossing_ones_are_cut() {
        let cam = camera();
        assert!(
            project_segment(&cam, DVec3::new(0.0, 0.0, -1.0), DVec3::new(1.0, 0.0, -2.0)).is_none()
        );
        let (a, b) = project_segment(&cam, DVec3::new(0.1, 0.0, -1.0), DVec3::new(0.1, 0.0, 1.0))
            .expect("cut");
        assert!(a.is_finite() && b.is_finite());
        assert!((b.x - (50.0 + cam.intrinsics.fx * 0.1)).abs() < 1e-9);
    }
}
