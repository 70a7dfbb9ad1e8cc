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
