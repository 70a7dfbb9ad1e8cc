//! The pieces of one reflector among the planar structures of a proposal
//! (`super::propose`): the wall around a pane, the face of its frame a few centimetres in
//! front, each perhaps in pieces as RANSAC's draws fall. A candidate's glass is where the sight
//! lines through any of them cross, laid onto the candidate's plane.
use glam::DVec3;

use super::propose::{PlaneCandidate, ProposalSettings};
use super::see_through::{SeeThrough, crossing};
use super::structures::{Structure, hulls_touch};
use crate::scene::{Camera, ReflectionPlane};

/// What tells the parts of a candidate's reflector from other structures.
pub(super) struct Reflector<'a> {
    pub structures: &'a [Structure],
    /// A part lies within this distance of the candidate's plane.
    pub offset: f64,
    /// The proposal's grid cell: see-through regions this close meet.
    pub cell: f64,
    pub settings: &'a ProposalSettings,
}

/// What [`Reflector::take_parts`] found.
pub(super) struct Parts {
    /// The parts as rejected candidates, each saying whose reflector it is part of.
    pub rejected: Vec<PlaneCandidate>,
    /// Their structure indices.
    pub structures: Vec<usize>,
    /// The candidate's plane over its whole reflector ([`whole_reflector_plane`]); None without
    /// parts or region.
    pub plane: Option<ReflectionPlane>,
}

impl Reflector<'_> {
    /// The entries of `scored` (structure index, sight lines, candidate) that are parts of the
    /// reflector of structure `k`, whose see-through rectangle is `glass`: parallel to it within
    /// the merge angle, within [`Self::offset`] of its plane, and either touching it
    /// ([`hulls_touch`]) or seen through where `glass` is or next to it ([`rectangles_meet`]
    /// within [`pane_gap`]). A wall that the pane splits into pieces that do not touch (left and
    /// right of the glass) gives each piece the sight lines through the part of the pane inside
    /// its hull.
    pub fn parts_of(
        &self,
        k: usize,
        glass: Option<ReflectionPlane>,
        scored: &[(usize, SeeThrough, PlaneCandidate)],
    ) -> Vec<usize> {
        let a = &self.structures[k];
        let cos_max = self.settings.merge_angle_deg.to_radians().cos();
        (0..scored.len())
            .filter(|&m| {
                let (j, _, other) = &scored[m];
                let b = &self.structures[*j];
                let near = *j != k
                    && a.normal.dot(b.normal).abs() >= cos_max
                    && a.signed_distance(b.point).abs() <= self.offset;
                let same_glass = || match (glass, other.plane) {
                    (Some(pa), Some(pb)) => {
                        rectangles_meet(&pa, &pb, pane_gap(&pa, &pb, self.cell))
                    }
                    _ => false,
                };
                near && (hulls_touch(a, b, 0.0) || same_glass())
            })
            .collect()
    }

    /// The parts of the reflector of structure `k` ([`Self::parts_of`]), whose candidate is `c`
    /// (the `index`-th proposed) with sight lines `seen` and camera side `front`, and its plane
    /// over all of them.
    #[allow(clippy::too_many_arguments)]
    pub fn take_parts(
        &self,
        k: usize,
        c: &PlaneCandidate,
        seen: &SeeThrough,
        scored: &[(usize, SeeThrough, PlaneCandidate)],
        index: usize,
        front: DVec3,
        sight: &Sight,
    ) -> Parts {
        let s = &self.structures[k];
        let whole = |of_k: &[usize]| {
            let parts_seen: Vec<&SeeThrough> = of_k.iter().map(|&m| &scored[m].1).collect();
            (!of_k.is_empty())
                .then(|| whole_reflector_plane(s, front, seen, &parts_seen, sight, self.cell))
                .flatten()
        };
        // The parts' sight lines widen the candidate's rectangle, which can then meet a piece
        // it did not (a frame in three pieces, the middle one seen through with the first): the
        // parts are looked for again over the wider rectangle until none is added.
        let mut of_k = self.parts_of(k, c.plane, scored);
        let mut plane = whole(&of_k);
        for _ in 0..PART_ROUNDS {
            let more: Vec<usize> = self
                .parts_of(k, plane.or(c.plane), scored)
                .into_iter()
                .filter(|m| !of_k.contains(m))
                .collect();
            if more.is_empty() {
                break;
            }
            of_k.extend(more);
            of_k.sort_unstable();
            plane = whole(&of_k);
        }
        let rejected = of_k
            .iter()
            .map(|&m| {
                let (j, _, other) = &scored[m];
                let apart = s.signed_distance(self.structures[*j].point).abs();
                let why = format!(
                    "part of candidate {index}'s reflector ({apart:.3} in front or behind)"
                );
                PlaneCandidate { rejected: Some(why), ..other.clone() }
            })
            .collect();
        Parts { rejected, structures: of_k.iter().map(|&m| scored[m].0).collect(), plane }
    }
}

/// The share of the shortest side of two see-through rectangles (at least a grid cell) by which
/// they may lie apart and still be one reflector's. The pieces of a frame or wall that RANSAC
/// draws apart see through the pane in pieces of their own, and between them lies a strip that
/// neither piece's hull holds; with a cell's gap alone the pane came as two candidates, and the
/// trial kept one piece (docs/RESULTS.md, "Planes without masks"; measured with
/// `examples/propose_probe.rs --seeds N`). Panes between mullions, or windows a narrow pier
/// apart, are one candidate too: a facade of panes in one plane.
pub const PANE_GAP_SHARE: f64 = 0.5;

/// How many times [`Reflector::take_parts`] looks for more parts over the rectangle its parts
/// widened: each round can add a piece next to the last.
const PART_ROUNDS: usize = 4;

/// How far apart see-through rectangles `a` and `b` may lie to be one reflector's: the
/// [`PANE_GAP_SHARE`] of their shortest side, at least a grid cell `cell`.
fn pane_gap(a: &ReflectionPlane, b: &ReflectionPlane, cell: f64) -> f64 {
    let shortest = a.width.min(a.height).min(b.width).min(b.height);
    (PANE_GAP_SHARE * shortest).max(cell)
}

/// Whether two rectangles in (nearly) one plane overlap or come within `gap` of each other in
/// it: no in-plane axis of either separates their projections by more than `gap`.
pub(super) fn rectangles_meet(a: &ReflectionPlane, b: &ReflectionPlane, gap: f64) -> bool {
    let half_extent = |r: &ReflectionPlane, e: DVec3| {
        0.5 * (r.width * r.axis.normalize().dot(e).abs()
            + r.height * r.bitangent().normalize().dot(e).abs())
    };
    [a.axis, a.bitangent(), b.axis, b.bitangent()].iter().all(|e| {
        let e = e.normalize();
        let apart = (a.centre - b.centre).dot(e).abs();
        apart <= half_extent(a, e) + half_extent(b, e) + gap
    })
}

/// The points and cameras of the sight lines, and the inlier distance.
pub(super) struct Sight<'a> {
    pub points: &'a [DVec3],
    pub cameras: &'a [&'a Camera],
    pub threshold: f64,
}

/// The glass plane of a candidate on structure `s` (facing `front`, its cameras' side) over the
/// see-through region of its whole reflector: its own sight lines (`seen`) and, outside its
/// hull, its parts' (`parts_seen`) whose points lie behind it, crossed with its plane. Inside
/// its hull its own holes say where the glass is: a part behind it (the wall a mirror hangs
/// on, the mirrored room grown right behind the glass) is crossed where the frame is too.
/// Without this the candidate's own holes alone held a part of the pane: on two of the
/// showcase's step-200 checkpoints, 1.8 to 2.1 of its 2.4 width in 3 of 20 seeds on each (the
/// `--seeds` sweep of `examples/propose_probe.rs`), and the refit cannot grow a rectangle.
fn whole_reflector_plane(
    s: &Structure,
    front: DVec3,
    seen: &SeeThrough,
    parts_seen: &[&SeeThrough],
    sight: &Sight,
    cell: f64,
) -> Option<ReflectionPlane> {
    let depth = |p: DVec3| (p - s.point).dot(front);
    let mut whole = seen.clone();
    for &(i, j) in parts_seen.iter().flat_map(|part| &part.sight_lines) {
        let (p, o) = (sight.points[i], sight.cameras[j].pose.centre());
        let (dp, dc) = (depth(p), depth(o));
        if dp >= -sight.threshold || dc <= sight.threshold {
            continue;
        }
        let q = s.to_plane(crossing(o, dc, p, dp));
        if !s.hull_contains(q, 0.0) {
            whole.crossings.push(q);
            whole.sight_lines.push((i, j));
        }
    }
    whole.region_plane(s, front, cell)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::propose::tests::grid;
    use crate::scene::{Intrinsics, Material, Pose};

    /// Points on z = 0 over `x` by `y`, 0.05 apart.
    fn wall(x: (f64, f64), y: (f64, f64)) -> Vec<DVec3> {
        grid(x, y, 0.05, |x, y| DVec3::new(x, y, 0.0))
    }

    /// Three pieces of one wall in z = 0 (x up to -0.4, -0.35 to 0.45, from 0.55), a pane over
    /// x -1.4 to 1.5 seen through each where its hull holds it, by a camera at z = 3 whose sight
    /// lines end 1 behind the wall. The middle piece's rectangle lies next to the left's; the
    /// right's, next to the middle's, lies too far from the left's to meet it.
    #[test]
    fn a_piece_next_to_the_one_a_part_widened_the_rectangle_to_is_a_part_too() {
        let pieces = [(-2.0, -0.4), (-0.35, 0.45), (0.55, 1.6)];
        let panes = [(-1.4, -0.5), (-0.3, 0.4), (0.6, 1.5)];
        let mut points: Vec<DVec3> = Vec::new();
        let mut structures = Vec::new();
        for piece in pieces {
            let first = points.len();
            points.extend(wall(piece, (0.0, 2.0)));
            let inliers = (first..points.len()).collect();
            structures.push(Structure::from_inliers(&points, inliers).expect("a plane"));
        }
        let eye = DVec3::new(0.0, 1.0, 3.0);
        let camera = Camera::new(
            "c",
            Intrinsics::from_fov_x(1.2, 64, 48),
            Pose::look_at(eye, DVec3::new(0.0, 1.0, 0.0), DVec3::Y),
        );
        let (cell, settings) = (0.05, ProposalSettings::default());
        let mut scored = Vec::new();
        for (k, pane) in panes.iter().enumerate() {
            let mut seen = SeeThrough::default();
            for q in wall(*pane, (0.5, 1.5)) {
                seen.points.push(points.len());
                seen.sight_lines.push((points.len(), 0));
                seen.crossings.push(structures[k].to_plane(q));
                // Behind the wall on the camera's sight line through q.
                points.push(eye + (q - eye) * (4.0 / 3.0));
            }
            let plane = seen.region_plane(&structures[k], DVec3::Z, cell);
            let candidate = PlaneCandidate {
                plane,
                support: structures[k].inliers.len(),
                seen_through: seen.points.len(),
                seen_fraction: 0.5,
                cameras_in_front: 1.0,
                structure_size: (1.0, 1.0),
                planarity: 1.0,
                wall_planarity: 1.0,
                opening_of: None,
                opening: None,
                rejected: None,
            };
            scored.push((k, seen, candidate));
        }
        let reflector =
            Reflector { structures: &structures, offset: 0.1, cell, settings: &settings };
        // The left piece's own rectangle meets the middle's and not the right's.
        let left = scored[0].2.plane.expect("a rectangle");
        let right = scored[2].2.plane.expect("a rectangle");
        assert_eq!(reflector.parts_of(0, Some(left), &scored), vec![1]);
        assert!(!rectangles_meet(&left, &right, pane_gap(&left, &right, cell)));
        let cameras = [&camera];
        let sight = Sight { points: &points, cameras: &cameras, threshold: 0.01 };
        let (c, seen) = (scored[0].2.clone(), scored[0].1.clone());
        let parts = reflector.take_parts(0, &c, &seen, &scored, 0, DVec3::Z, &sight);
        assert_eq!(parts.structures, vec![1, 2]);
        let plane = parts.plane.expect("the whole reflector");
        let width =
            if plane.axis.x.abs() > plane.axis.y.abs() { plane.width } else { plane.height };
        assert!((2.8..3.1).contains(&width), "the whole pane: {plane:?}");
    }

    fn rectangle(centre: DVec3, axis: DVec3, width: f64, height: f64) -> ReflectionPlane {
        ReflectionPlane::new(centre, DVec3::Z, axis, width, height, Material::Glass)
    }

    #[test]
    fn rectangles_meet_when_they_overlap_or_lie_within_the_gap_and_not_beyond() {
        let a = rectangle(DVec3::ZERO, DVec3::X, 2.0, 1.0);
        // Side by side, 0.1 apart along x.
        let b = rectangle(DVec3::new(2.1, 0.0, 0.0), DVec3::X, 2.0, 1.0);
        assert!(rectangles_meet(&a, &b, 0.15) && !rectangles_meet(&a, &b, 0.05));
        // Overlapping, turned 45 degrees.
        let c = rectangle(DVec3::new(1.0, 0.5, 0.0), DVec3::new(1.0, 1.0, 0.0), 0.5, 0.5);
        assert!(rectangles_meet(&a, &c, 0.0));
        // Past a's corner: 0.32 apart along x and y, 0.65 along the turned rectangle's axis.
        let d = rectangle(DVec3::new(1.6, 1.1, 0.0), DVec3::new(1.0, 1.0, 0.0), 0.4, 0.4);
        assert!(!rectangles_meet(&a, &d, 0.5));
        assert!(rectangles_meet(&a, &d, 0.7));
    }
}
