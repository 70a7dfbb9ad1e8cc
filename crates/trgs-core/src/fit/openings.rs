//! A pane turned in its opening (a window ajar, a glass door left open) is a reflector of its
//! own, but the wall around it, with far more points seen through it, is taken first and takes
//! every sight line through that opening; the turned pane's frame, a structure inside the
//! opening, is left with the few sight lines that pass its own frame. The opening belongs to the
//! pane: [`opening_holding`] finds it and [`hand_over`] moves its sight lines to the pane, where
//! they cross the pane's plane.
use glam::{DVec2, DVec3};

use super::hull::{OrientedBox, min_area_box};
use super::see_through::{SeeThrough, crossing};
use super::structures::{Structure, grid_components, polygon_area};
use crate::scene::Camera;

/// At least this fraction of a pane's points lie in the opening (projected onto the wall).
const PANE_IN_OPENING: f64 = 0.5;

/// A pane turned in its opening meets the wall's plane where it turns (its hinge, or its middle):
/// some of its points lie within this many grid cells of that plane (the frame's depth). A tilted
/// board or shelf behind a shop window lies farther (a final model of the family's
/// large-pane-lights holds one 35 degrees off the glass, 0.79 behind it: 8 cells).
const PANE_MEETS_WALL: f64 = 2.0;

/// An opening is a hole in a wall: its crossings' box covers at most this fraction of the wall's
/// hull. The structure around a mirror's glass is its frame, which the glass fills (a turned
/// mirror's frame on a drawn member of the family: 91%; the two-turned-panes member's wall
/// around its turned pane's opening: 24%), and a structure inside that is the room the mirror
/// shows, not a pane turned in it.
const MAX_OPENING_SHARE: f64 = 0.5;

/// A pane is turned in its opening by at most this angle (degrees). The faces around an opening
/// (a sill, a reveal, the frame's sides) also meet the wall's plane across it, at right angles
/// or nearly: the structures that `examples/propose_probe` finds there on the scene family's
/// stage-1 models meet it at 58 to 86 degrees.
const MAX_TURN_DEG: f64 = 45.0;

/// A pane turned in its opening by less than this angle (degrees) is left to the wall's
/// candidate: the refit of a kept plane turns it onto the frame around its glass by up to as
/// much (`OUTLINE_TURN_DEG` in trgs-train's `run::plane_refit`). Below it, what the proposal
/// finds over an opening is mostly not a pane: over the showcase's fixed pane, a structure
/// turned 2.5 to 6.5 degrees took the opening in 13 of 40 RANSAC seeds on two step-200
/// checkpoints (`examples/propose_probe.rs --seeds`), and the wall's candidate was left with
/// the stray sight lines past it. The family's pane turned in its opening is turned 20 degrees.
const MIN_TURN_DEG: f64 = 10.0;

/// An opening in a wall: some of the wall's see-through crossings, and where the pane in it
/// lies.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Opening {
    /// Indices of the wall's crossings in the opening, ascending.
    pub crossings: Vec<usize>,
    /// The crossings' minimum-area box (the wall's plane coordinates), grown by a grid cell.
    pub bounds: OrientedBox,
    /// How far from the wall's plane a pane turned in the opening reaches: half the box's
    /// longer side.
    pub reach: f64,
}

impl Opening {
    /// Whether the plane of `pane` meets the wall's plane across the opening (the line a pane
    /// turns about in its opening, on an edge or through the middle): the pane's signed distance
    /// changes sign, or is zero, over the opening's corners.
    fn pivots_in(&self, wall: &Structure, pane: &Structure) -> bool {
        let d = self.bounds.corners().map(|q| pane.signed_distance(wall.to_world(q)));
        d.iter().any(|&x| x <= 0.0) && d.iter().any(|&x| x >= 0.0)
    }

    /// Whether `p` lies in the space a pane turned in the opening sweeps.
    fn holds(&self, wall: &Structure, p: DVec3) -> bool {
        wall.signed_distance(p).abs() <= self.reach && self.bounds.contains(wall.to_plane(p), 0.0)
    }
}

/// The opening of `wall` that `pane` is turned in: a connected group of the wall's crossings
/// (grid cell `cell`) that is a hole in the wall ([`MAX_OPENING_SHARE`]), across which the
/// pane's plane meets the wall's ([`Opening::pivots_in`]), and whose box, grown by a cell, holds
/// at least [`PANE_IN_OPENING`] of the pane's points projected onto the wall's plane, those
/// points lying within half the box's longer side of that plane (a pane turned in its opening
/// stays there; the room seen through it lies farther) and some of them where it meets the wall
/// ([`PANE_MEETS_WALL`]). None where there is none, where the two are parallel within
/// `parallel_deg` (a structure parallel to the wall in its opening is the pane's frame, part of
/// the wall's reflector) or turned less than [`MIN_TURN_DEG`], and where they meet at more than
/// [`MAX_TURN_DEG`].
pub(super) fn opening_holding(
    wall: &Structure,
    wall_seen: &SeeThrough,
    pane: &Structure,
    points: &[DVec3],
    cell: f64,
    parallel_deg: f64,
) -> Option<Opening> {
    let cos = wall.normal.dot(pane.normal).abs();
    if cos >= parallel_deg.to_radians().cos()
        || cos > MIN_TURN_DEG.to_radians().cos()
        || cos < MAX_TURN_DEG.to_radians().cos()
        || pane.inliers.is_empty()
    {
        return None;
    }
    for group in grid_components(&wall_seen.crossings, cell) {
        let coords: Vec<DVec2> = group.iter().map(|&k| wall_seen.crossings[k]).collect();
        let Some(b) = min_area_box(&coords) else { continue };
        if b.area() > MAX_OPENING_SHARE * polygon_area(&wall.hull) {
            continue;
        }
        let bounds =
            OrientedBox { width: b.width + 2.0 * cell, height: b.height + 2.0 * cell, ..b };
        let mut opening = Opening { crossings: group, bounds, reach: 0.5 * b.width.max(b.height) };
        if !opening.pivots_in(wall, pane) {
            continue;
        }
        let inside = pane.inliers.iter().filter(|&&i| opening.holds(wall, points[i])).count();
        let nearest = pane
            .inliers
            .iter()
            .map(|&i| wall.signed_distance(points[i]).abs())
            .fold(f64::INFINITY, f64::min);
        if inside as f64 >= PANE_IN_OPENING * pane.inliers.len() as f64
            && nearest <= PANE_MEETS_WALL * cell
        {
            opening.crossings.sort_unstable();
            return Some(opening);
        }
    }
    None
}

/// Move the crossings of `opening` in `wall` from `from` (the wall's) to `to`, whose structure
/// is `pane` seen from `front`: each of their sight lines crosses the pane's plane instead,
/// where the camera stands more than `threshold` in front of it and the point more than
/// `threshold` behind it, and that crossing counts where it lies in the opening's space
/// ([`Opening::holds`]; a sight line nearly along the pane's plane crosses it far away) and not
/// on the pane's frame ([`Structure::blocks`]). A point stays seen through `from` while any of
/// its crossings remains there. `cameras` is the slice `from`'s sight lines index.
pub(super) fn hand_over(
    wall: &Structure,
    from: &mut SeeThrough,
    opening: &Opening,
    to: &mut SeeThrough,
    pane: &Structure,
    front: DVec3,
    points: &[DVec3],
    cameras: &[&Camera],
    threshold: f64,
) {
    let depth = |p: DVec3| (p - pane.point).dot(front);
    let mut moved = Vec::with_capacity(opening.crossings.len());
    for &k in &opening.crossings {
        let (i, j) = from.sight_lines[k];
        let (o, p) = (cameras[j].pose.centre(), points[i]);
        let (dc, dp) = (depth(o), depth(p));
        if dc > threshold && dp < -threshold {
            let x = crossing(o, dc, p, dp);
            let q = pane.to_plane(x);
            if opening.holds(wall, x) && !pane.blocks(q) {
                to.crossings.push(q);
                to.sight_lines.push((i, j));
                moved.push(i);
            }
        }
    }
    (from.crossings, from.sight_lines) = from
        .crossings
        .iter()
        .zip(&from.sight_lines)
        .enumerate()
        .filter(|(k, _)| opening.crossings.binary_search(k).is_err())
        .map(|(_, (&q, &s))| (q, s))
        .unzip();
    let mut still: Vec<usize> = from.sight_lines.iter().map(|s| s.0).collect();
    still.sort_unstable();
    from.points.retain(|i| still.binary_search(i).is_ok());
    to.points.extend(moved);
    to.points.sort_unstable();
    to.points.dedup();
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::see_through::see_through;
    use crate::scene::{Intrinsics, Pose};

    /// Points every `step` over `[x0, x1] x [y0, y1]`, mapped by `at`.
    fn grid(x: (f64, f64), y: (f64, f64), step: f64, at: impl Fn(f64, f64) -> DVec3) -> Vec<DVec3> {
        let n = |a: (f64, f64)| ((a.1 - a.0) / step).round() as usize;
        (0..=n(y))
            .flat_map(|j| (0..=n(x)).map(move |i| (x.0 + i as f64 * step, y.0 + j as f64 * step)))
            .map(|(a, b)| at(a, b))
            .collect()
    }

    #[test]
    fn a_pane_turned_in_an_opening_takes_it_and_a_parallel_frame_a_board_behind_or_a_rim_do_not() {
        // A wall in z = 0 with an opening over [0, 1] x [0, 1]; a pane's frame along the
        // opening's left edge, turned 20 degrees about it; a room behind at z = -2.
        let hole = |x: f64, y: f64| (0.0..1.0).contains(&x) && (0.0..1.0).contains(&y);
        let mut points: Vec<DVec3> =
            grid((-2.0, 3.0), (-1.0, 2.0), 0.05, |x, y| DVec3::new(x, y, 0.0))
                .into_iter()
                .filter(|p| !hole(p.x, p.y))
                .collect();
        let wall = Structure::from_inliers(&points, (0..points.len()).collect()).expect("wall");
        // The frame's left stile and half its rails, turned `deg` about the stile.
        let frame_turned = |deg: f64, points: &mut Vec<DVec3>| {
            let (s, c) = (deg.to_radians().sin(), deg.to_radians().cos());
            let first = points.len();
            let at = |u: f64, y: f64| DVec3::new(u * c, y, -u * s);
            points.extend(grid((0.0, 0.1), (0.0, 1.0), 0.02, at));
            points.extend(grid((0.1, 0.5), (0.0, 0.04), 0.02, at));
            points.extend(grid((0.1, 0.5), (0.96, 1.0), 0.02, at));
            Structure::from_inliers(points, (first..points.len()).collect()).expect("frame")
        };
        let (s, c) = (20f64.to_radians().sin(), 20f64.to_radians().cos());
        let first = points.len();
        let turned = frame_turned(20.0, &mut points);
        let room = points.len();
        points.extend(grid((-1.0, 2.0), (-0.5, 1.5), 0.05, |x, y| DVec3::new(x, y, -2.0)));
        let k = Intrinsics::from_fov_x(1.2, 64, 48);
        let cameras: Vec<Camera> = [-0.3, 0.5, 1.3]
            .iter()
            .map(|&x| {
                let eye = DVec3::new(x, 0.5, 3.0);
                Camera::new("c", k, Pose::look_at(eye, DVec3::new(0.5, 0.5, 0.0), DVec3::Y))
            })
            .collect();
        let cameras: Vec<&Camera> = cameras.iter().collect();
        let front = if wall.normal.z > 0.0 { wall.normal } else { -wall.normal };
        let behind: Vec<usize> = (room..points.len()).collect();
        let mut seen = see_through(&wall, front, &points, &behind, &cameras, 0.01);
        assert!(seen.points.len() > 50, "the room is seen through the opening");
        let opening = opening_holding(&wall, &seen, &turned, &points, 0.08, 2.0).expect("opening");
        assert_eq!(opening.crossings.len(), seen.crossings.len(), "the one opening");
        // A frame parallel to the wall in the same opening is the wall's own.
        let stile = points.len();
        points.extend(grid((0.0, 0.1), (0.0, 1.0), 0.02, |x, y| DVec3::new(x, y, 0.0)));
        let flat =
            Structure::from_inliers(&points, (stile..points.len()).collect()).expect("stile");
        assert!(opening_holding(&wall, &seen, &flat, &points, 0.08, 2.0).is_none());
        // Nor is the same frame turned 5 degrees: the wall's candidate, turned by the refit.
        let nearly = frame_turned(5.0, &mut points);
        assert!(opening_holding(&wall, &seen, &nearly, &points, 0.08, 2.0).is_none());
        // A board turned 40 degrees whose plane meets the wall's across the opening, but which
        // stands 0.2 to 0.5 behind it, is not the opening's pane.
        let (s40, c40) = (40f64.to_radians().sin(), 40f64.to_radians().cos());
        let board = points.len();
        points.extend(grid((-0.2, 0.2), (0.2, 0.8), 0.02, |u, y| {
            DVec3::new(0.5 + u * c40, y, -0.35 - u * s40)
        }));
        let board =
            Structure::from_inliers(&points, (board..points.len()).collect()).expect("board");
        assert!(opening_holding(&wall, &seen, &board, &points, 0.08, 2.0).is_none());
        // Nor is a frame that its opening fills.
        let rim: Vec<usize> = (0..first)
            .filter(|&i| points[i].x > -0.18 && points[i].x < 1.18)
            .filter(|&i| points[i].y > -0.18 && points[i].y < 1.18)
            .collect();
        let rim = Structure::from_inliers(&points, rim).expect("rim");
        let rim_seen = see_through(&rim, front, &points, &behind, &cameras, 0.01);
        assert!(!rim_seen.crossings.is_empty());
        assert!(opening_holding(&rim, &rim_seen, &turned, &points, 0.08, 2.0).is_none());

        let pane_front = if turned.normal.z > 0.0 { turned.normal } else { -turned.normal };
        let mut pane_seen = SeeThrough::default();
        let n = opening.crossings.len();
        hand_over(
            &wall,
            &mut seen,
            &opening,
            &mut pane_seen,
            &turned,
            pane_front,
            &points,
            &cameras,
            0.01,
        );
        assert!(seen.points.is_empty() && seen.crossings.is_empty() && seen.sight_lines.is_empty());
        // Every sight line crosses the turned plane in the opening; those through the frame
        // are blocked there.
        let moved = pane_seen.crossings.len();
        assert!(moved > n / 2 && moved < n, "{moved} of {n}");
        assert!(pane_seen.crossings.iter().all(|&q| !turned.blocks(q)));
        assert_eq!(pane_seen.sight_lines.len(), moved);
        // The sight lines through the opening cross the turned plane about the opening: the
        // pane's extent along its plane is about the opening's 1 x 1 (0.94 to 1.15 wide).
        let b = min_area_box(&pane_seen.crossings).expect("a region");
        assert!((0.85..1.25).contains(&b.width) && (0.85..1.25).contains(&b.height), "{b:?}");
        let centre = turned.to_world(b.centre);
        assert!(centre.distance(DVec3::new(0.5 * c, 0.5, -0.5 * s)) < 0.15, "{centre}");
    }
}
