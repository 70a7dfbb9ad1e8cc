//! How well a plane explains the capture's glass masks: its rectangle projected into every
//! masked view against each label's pixels, pooled over the views (an intersection over union).
//! `merge` uses it to tell which blocks' planes are one pane (the label they explain best; the
//! capture's labels are the same in every block) and which of them saw it whole.
use crate::image::Image;
use crate::scene::{Camera, ReflectionPlane};
use glam::DVec2;

/// A plane's best-explained label and the pooled intersection over union with its pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LabelSupport {
    pub label: u8,
    pub iou: f64,
}

/// The label of `masks` (camera, label image at the camera's size) whose pixels `plane`'s
/// rectangle covers best, by intersection over union pooled over the views (a view where the
/// rectangle is partly behind the camera is left out); None when it covers no labelled pixel.
pub fn label_support(
    plane: &ReflectionPlane,
    masks: &[(&Camera, &Image<u8>)],
) -> Option<LabelSupport> {
    let (mut inter, mut union) = ([0u64; 256], [0u64; 256]);
    for (camera, mask) in masks {
        let Some(quad) = projected_quad(plane, camera) else { continue };
        let (w, h) = (mask.width as usize, mask.height as usize);
        let mut total = [0u64; 256];
        for &l in &mask.data {
            total[l as usize] += 1;
        }
        let (mut inside, mut area) = ([0u64; 256], 0u64);
        let (lo, hi) = quad_bounds(&quad);
        let (x0, x1) = (lo.x.floor().max(0.0) as usize, (hi.x.ceil().max(0.0) as usize).min(w));
        let (y0, y1) = (lo.y.floor().max(0.0) as usize, (hi.y.ceil().max(0.0) as usize).min(h));
        for y in y0..y1 {
            for x in x0..x1 {
                if contains(&quad, DVec2::new(x as f64 + 0.5, y as f64 + 0.5)) {
                    area += 1;
                    inside[mask.data[y * w + x] as usize] += 1;
                }
            }
        }
        for l in 1..256 {
            if total[l] > 0 || area > 0 {
                inter[l] += inside[l];
                union[l] += area + total[l] - inside[l];
            }
        }
    }
    (1..256usize)
        .filter(|&l| inter[l] > 0)
        .map(|l| LabelSupport { label: l as u8, iou: inter[l] as f64 / union[l] as f64 })
        .max_by(|a, b| a.iou.total_cmp(&b.iou))
}

/// The rectangle's corners in `camera`'s pixels; None when one is behind the camera.
fn projected_quad(plane: &ReflectionPlane, camera: &Camera) -> Option<[DVec2; 4]> {
    let c = plane.corners();
    Some([
        camera.project(c[0])?,
        camera.project(c[1])?,
        camera.project(c[2])?,
        camera.project(c[3])?,
    ])
}

fn quad_bounds(q: &[DVec2; 4]) -> (DVec2, DVec2) {
    q.iter().fold((q[0], q[0]), |(lo, hi), &p| (lo.min(p), hi.max(p)))
}

/// Whether `p` lies in the convex quadrilateral `q` (either winding).
fn contains(q: &[DVec2; 4], p: DVec2) -> bool {
    let side = |a: DVec2, b: DVec2| (b - a).perp_dot(p - a);
    let s: [f64; 4] = [side(q[0], q[1]), side(q[1], q[2]), side(q[2], q[3]), side(q[3], q[0])];
    s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Intrinsics, Material, Pose};
    use glam::DVec3;

    /// A camera 4 m in front of the plane z = 0, looking at it.
    fn camera() -> Camera {
        let pose = Pose::look_at(DVec3::new(0.0, 0.0, 4.0), DVec3::ZERO, DVec3::NEG_Y);
        Camera::new("v", Intrinsics::from_fov_x(60f64.to_radians(), 96, 72), pose)
    }

    fn pane(cx: f64, width: f64) -> ReflectionPlane {
        ReflectionPlane::new(
            DVec3::new(cx, 0.0, 0.0),
            DVec3::Z,
            DVec3::X,
            width,
            1.0,
            Material::Glass,
        )
    }

    /// The mask a camera sees of `planes`, labelled 1, 2, ... in order.
    fn mask_of(camera: &Camera, planes: &[ReflectionPlane]) -> Image<u8> {
        let mut m = Image::<u8>::new(camera.width(), camera.height(), 1);
        for (k, p) in planes.iter().enumerate() {
            let q = projected_quad(p, camera).expect("in front");
            for y in 0..camera.height() {
                for x in 0..camera.width() {
                    if contains(&q, DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5)) {
                        m.set(x, y, 0, k as u8 + 1);
                    }
                }
            }
        }
        m
    }

    #[test]
    fn a_plane_is_told_by_the_label_it_covers_and_a_part_of_it_scores_less() {
        let cam = camera();
        let truth = [pane(-1.0, 1.2), pane(1.2, 1.6)];
        let mask = mask_of(&cam, &truth);
        let masks = [(&cam, &mask)];
        let whole = label_support(&truth[1], &masks).expect("support");
        assert_eq!(whole.label, 2);
        assert!(whole.iou > 0.97, "{whole:?}");
        let half = label_support(&pane(0.8, 0.8), &masks).expect("support");
        assert_eq!(half.label, 2);
        assert!(half.iou > 0.4 && half.iou < 0.6, "{half:?}");
        // A plane off to one side covers no glass.
        assert_eq!(label_support(&pane(3.5, 0.3), &masks), None);
    }
}
