//! The "SfM" sparse points of the synthetic scene: surface points seen by at least two cameras,
//! with colours and COLMAP-like tracks, and a share drawn on the pane frames.
use glam::DVec3;

use super::generate::{Layout, local_ray, project_through};
use super::geom::Ray;
use trgs_core::rng::Rng;

/// Standard deviation of the position noise of the sparse points, in metres.
const POINT_NOISE: f64 = 0.003;

/// Points (position, colour) and, per point, the cameras that see it.
pub(crate) type Points = (Vec<([f64; 3], [u8; 3])>, Vec<Vec<usize>>);

/// A uniform random point on the surface of a box.
fn point_on_box(rng: &mut Rng, min: DVec3, max: DVec3) -> DVec3 {
    let e = max - min;
    let areas = [e.y * e.z, e.x * e.z, e.x * e.y];
    let mut pick = rng.uniform() * (areas[0] + areas[1] + areas[2]);
    let mut axis = 2;
    for (a, &area) in areas.iter().enumerate() {
        if pick < area {
            axis = a;
            break;
        }
        pick -= area;
    }
    let mut p = min + DVec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * e;
    p[axis] = if rng.uniform() < 0.5 { min[axis] } else { max[axis] };
    p
}

/// Sparse points: surface points seen by at least two cameras (visibility by ray casting; panes
/// do not block), with their shaded colour and a little position noise. A share of them is drawn
/// on the frames so that the plane initialisation finds the pane's plane.
pub(crate) fn sparse_points(layout: &Layout, target: usize, seed: u64) -> Points {
    let mut rng = Rng::new(seed ^ 0x5EED_0F5F_u64);
    let (mut points, mut tracks) = (Vec::new(), Vec::new());
    let cams = &layout.cameras;
    if cams.is_empty() {
        return (points, tracks);
    }
    let eyes: Vec<DVec3> =
        cams.iter().map(|c| layout.placement.point_to_local(c.pose.centre())).collect();
    let max_attempts = 50 * target + 100;
    for _ in 0..max_attempts {
        if points.len() >= target {
            break;
        }
        let p_local = if !layout.frame_boxes.is_empty() && rng.uniform() < 0.15 {
            let frame = layout.frame_boxes[rng.below(layout.frame_boxes.len())];
            let p = point_on_box(&mut rng, frame.min, frame.max);
            frame.turn.map_or(p, |t| t.point(p))
        } else {
            let cam = &cams[rng.below(cams.len())];
            let px = rng.range(0.0, f64::from(cam.width()));
            let py = rng.range(0.0, f64::from(cam.height()));
            let ray = local_ray(layout, cam, px, py);
            match layout.world.hit_opaque(&ray) {
                Some(hit) => ray.at(hit.t),
                None => continue,
            }
        };
        let p_world = layout.placement.point_to_world(p_local);
        let seen: Vec<usize> = (0..cams.len())
            .filter(|&i| {
                project_through(layout.lens, &cams[i], p_world).is_some()
                    && layout.world.visible(eyes[i], p_local)
            })
            .collect();
        let Some(&first) = seen.first() else { continue };
        if seen.len() < 2 {
            continue;
        }
        // The colour is the shaded surface colour (view-independent), as triangulation would
        // average it; trace from a camera that sees the point to get its surface and normal.
        let to = p_local - eyes[first];
        let ray = Ray::new(eyes[first], to.normalize());
        let Some(hit) = layout.world.hit_opaque(&ray) else { continue };
        let colour = layout.world.shade(&hit);
        let noise = DVec3::new(rng.normal(), rng.normal(), rng.normal()) * POINT_NOISE;
        let noisy = p_world + noise;
        let track: Vec<usize> = seen
            .into_iter()
            .filter(|&i| project_through(layout.lens, &cams[i], noisy).is_some())
            .collect();
        if track.len() < 2 {
            continue;
        }
        let c = colour.clamp(DVec3::ZERO, DVec3::ONE) * 255.0 + DVec3::splat(0.5);
        points.push((noisy.to_array(), [c.x as u8, c.y as u8, c.z as u8]));
        tracks.push(track);
    }
    (points, tracks)
}
