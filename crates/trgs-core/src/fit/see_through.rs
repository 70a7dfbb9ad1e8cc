//! The evidence that a planar structure holds glass or a mirror: points that the cameras in front
//! of it see *through* it. An opaque wall hides what lies behind it, so a point behind the plane
//! whose sight lines cross the plane inside the structure is seen through an opening in it: the
//! room behind a window (transmission) or the virtual geometry a reflector shows (a mirror image
//! lies behind the mirror). Where those sight lines cross the plane outlines the see-through
//! region: the initial extent of a candidate plane.
use glam::{DVec2, DVec3};
use std::collections::HashMap;

use super::hull::{OrientedBox, min_area_box};
use super::structures::{Structure, grid_cell, grid_components};
use crate::scene::{Camera, Material, ReflectionPlane};

/// The points seen through a structure and where their sight lines cross it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SeeThrough {
    /// Indices of the points seen through the structure, ascending.
    pub points: Vec<usize>,
    /// Plane coordinates of the crossings of their sight lines inside the structure.
    pub crossings: Vec<DVec2>,
    /// The sight line of each crossing: the point's index and the camera's (in the slice the
    /// cameras were given in).
    pub sight_lines: Vec<(usize, usize)>,
}

/// A connected group of crossings with at least this fraction of the largest group's crossings
/// is part of a see-through region: the panes of a facade, which its mullions split into groups
/// of their own, are one region, while a few stray sight lines are not.
pub const REGION_GROUP_FRACTION: f64 = 0.2;

/// A grid cell is part of a see-through region when it holds at least this fraction of the
/// crossings of the median crossing's cell (crossings ranked by their cell's count). Every
/// camera's sight lines to the many points behind a pane cross the pane's own cells; what lies
/// just behind a frame's face or beside the glass (the wall a mirror hangs on, a few centimetres
/// behind its frame, and the sparse points on it) is crossed by few, in the frame's sampling
/// gaps. Left in, those crossings widened a framed mirror's first rectangle over its frame: its
/// glass Gaussians trained there and its plane stayed on the frame's face. Higher fractions cut
/// into panes seen by few cameras, where fewer sight lines cross near the edges (probed on
/// plain-run checkpoints: docs/RESULTS.md, "Planes without masks").
pub const REGION_CELL_DENSITY: f64 = 0.3;

impl SeeThrough {
    /// The crossings `indices` (into [`Self::crossings`]) alone, with their sight lines and
    /// points.
    pub fn only(&self, indices: &[usize]) -> Self {
        let crossings = indices.iter().map(|&k| self.crossings[k]).collect();
        let sight_lines: Vec<(usize, usize)> =
            indices.iter().map(|&k| self.sight_lines[k]).collect();
        let mut points: Vec<usize> = sight_lines.iter().map(|s| s.0).collect();
        points.sort_unstable();
        points.dedup();
        Self { points, crossings, sight_lines }
    }

    /// The rectangle (plane coordinates) of the see-through region: the minimum-area box of the
    /// crossings in grid cells of size `cell` that hold at least [`REGION_CELL_DENSITY`] of the
    /// median crossing's cell's count and, of those, in the connected groups of cells that hold
    /// at least [`REGION_GROUP_FRACTION`] of the largest group's crossings; widened by half a
    /// cell on each side. `None` without crossings or for a region of no area.
    pub fn region(&self, cell: f64) -> Option<OrientedBox> {
        let crossings = dense_crossings(&self.crossings, cell);
        let groups = grid_components(&crossings, cell);
        let least = REGION_GROUP_FRACTION * groups.first()?.len() as f64;
        let inside: Vec<DVec2> = groups
            .iter()
            .take_while(|g| g.len() as f64 >= least)
            .flatten()
            .map(|&k| crossings[k])
            .collect();
        // A cell across the glass's edge is partly glass, so crossed by fewer sight lines, and
        // may be left out: half a cell more on each side. The trial's refit trims a rectangle
        // to its learned glass but cannot grow it past where its glass Gaussians started.
        min_area_box(&inside).filter(|b| b.width > 0.0 && b.height > 0.0).map(|b| OrientedBox {
            width: b.width + cell,
            height: b.height + cell,
            ..b
        })
    }
}

impl SeeThrough {
    /// The glass plane over [`Self::region`] in `structure`'s plane (whose crossings these
    /// are), its normal `front` (toward the cameras).
    pub fn region_plane(
        &self,
        structure: &Structure,
        front: DVec3,
        cell: f64,
    ) -> Option<ReflectionPlane> {
        let b = self.region(cell)?;
        let axis = structure.basis.0 * b.axis.x + structure.basis.1 * b.axis.y;
        let centre = structure.to_world(b.centre);
        Some(ReflectionPlane::new(centre, front, axis, b.width, b.height, Material::Glass))
    }
}

/// The crossings in grid cells of size `cell` that hold at least [`REGION_CELL_DENSITY`] of the
/// crossings of the median crossing's cell.
fn dense_crossings(crossings: &[DVec2], cell: f64) -> Vec<DVec2> {
    let cell_of = |q: &DVec2| grid_cell(*q, cell);
    let mut counts: HashMap<(i64, i64), usize> = HashMap::new();
    for q in crossings {
        *counts.entry(cell_of(q)).or_default() += 1;
    }
    // The median over the crossings, not over the cells: a wide frame of sparse cells can hold
    // more cells than the pane does, but fewer crossings.
    let mut sorted: Vec<usize> = crossings.iter().map(|q| counts[&cell_of(q)]).collect();
    sorted.sort_unstable();
    let Some(&median) = sorted.get(sorted.len() / 2) else { return Vec::new() };
    let least = REGION_CELL_DENSITY * median as f64;
    crossings.iter().copied().filter(|q| counts[&cell_of(q)] as f64 >= least).collect()
}

/// The points among `candidates` that the `cameras` see through holes in `structure`
/// ([`Structure::is_hole`]), whose `front` is the side the cameras stand on (`front` is the
/// structure's normal or its negation): a point at least `threshold` behind the plane counts when
/// the sight lines of at least two of the front cameras that have it in view (one, if only one
/// does) cross the plane in a hole. A sight line that crosses where the structure has points is
/// blocked there, and one that crosses outside the hull passes the structure by.
pub fn see_through(
    structure: &Structure,
    front: DVec3,
    points: &[DVec3],
    candidates: &[usize],
    cameras: &[&Camera],
    threshold: f64,
) -> SeeThrough {
    let depth = |p: DVec3| (p - structure.point).dot(front);
    let front_cameras: Vec<(usize, &Camera, DVec3, f64)> = cameras
        .iter()
        .enumerate()
        .map(|(j, c)| (j, *c, c.pose.centre()))
        .filter_map(|(j, c, o)| (depth(o) > threshold).then_some((j, c, o, depth(o))))
        .collect();
    let mut out = SeeThrough::default();
    let mut crossings = Vec::new();
    for &i in candidates {
        let p = points[i];
        let dp = depth(p);
        if dp >= -threshold {
            continue;
        }
        crossings.clear();
        let mut in_view = 0usize;
        for &(j, camera, o, dc) in &front_cameras {
            if !camera.sees(p) {
                continue;
            }
            in_view += 1;
            let q = structure.to_plane(crossing(o, dc, p, dp));
            if structure.is_hole(q) {
                crossings.push((q, (i, j)));
            }
        }
        if in_view > 0 && crossings.len() >= in_view.min(2) {
            out.points.push(i);
            out.crossings.extend(crossings.iter().map(|c| c.0));
            out.sight_lines.extend(crossings.iter().map(|c| c.1));
        }
    }
    out
}

/// Where the sight line from a camera at `o`, `dc` in front of a plane, to a point `p`, `dp`
/// in front of it (negative: behind), meets the plane: where the depth falls to zero.
pub(super) fn crossing(o: DVec3, dc: f64, p: DVec3, dp: f64) -> DVec3 {
    o + (p - o) * (dc / (dc - dp))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Intrinsics, Pose};

    fn camera_at(eye: DVec3) -> Camera {
        // A wide lens (103 degrees) so that the point past the wall's edge is in view.
        let k = Intrinsics::from_fov_x(1.8, 64, 48);
        Camera::new("c", k, Pose::look_at(eye, DVec3::ZERO, DVec3::Y))
    }

    /// A wall in z = 0 spanning [-2, 2]^2 in x and y with a 1 x 1 hole in the middle.
    fn wall() -> (Vec<DVec3>, Structure) {
        let mut points = Vec::new();
        for iy in -20..=20 {
            for ix in -20..=20 {
                let (x, y) = (ix as f64 * 0.1, iy as f64 * 0.1);
                if x.abs() > 0.45 || y.abs() > 0.45 {
                    points.push(DVec3::new(x, y, 0.0));
                }
            }
        }
        let inliers = (0..points.len()).collect();
        let s = Structure::from_inliers(&points, inliers).expect("a plane");
        (points, s)
    }

    #[test]
    fn points_seen_through_the_hole_count_and_those_behind_the_wall_or_past_it_do_not() {
        let (mut points, s) = wall();
        let front = if s.normal.z > 0.0 { s.normal } else { -s.normal };
        let through = points.len();
        points.push(DVec3::new(0.1, 0.2, -1.0));
        // In front of the wall; behind its solid part; behind it but seen past its edge (x = 2).
        points.push(DVec3::new(0.0, 0.0, 0.5));
        let blocked = DVec3::new(1.5, 1.5, -1.0);
        points.push(blocked);
        let past_the_edge = DVec3::new(3.0, 0.0, -0.5);
        points.push(past_the_edge);
        let cams: Vec<Camera> =
            [-0.5, 0.0, 0.5].iter().map(|&x| camera_at(DVec3::new(x, 0.0, 3.0))).collect();
        let cams: Vec<&Camera> = cams.iter().collect();
        assert!(cams.iter().all(|c| c.sees(past_the_edge) && c.sees(blocked)), "all in view");
        let all: Vec<usize> = (0..points.len()).collect();
        let seen = see_through(&s, front, &points, &all, &cams, 0.01);
        assert_eq!(seen.points, vec![through]);
        assert_eq!(seen.crossings.len(), 3, "one crossing per camera");
        assert!(seen.crossings.iter().all(|q| q.x.abs() < 0.5 && q.y.abs() < 0.5));
        // From behind the wall (its back side as front) nothing is behind it from those cameras.
        let seen = see_through(&s, -front, &points, &all, &cams, 0.01);
        assert!(seen.points.is_empty());
    }

    #[test]
    fn the_region_spans_groups_of_like_size_and_leaves_small_ones_out() {
        // Two panes of 200 crossings each, 1 apart, and a group of 30 beyond them.
        let mut crossings = Vec::new();
        for x0 in [0.0, 2.0] {
            for iy in 0..10 {
                for ix in 0..20 {
                    crossings.push(DVec2::new(x0 + ix as f64 * 0.05, iy as f64 * 0.05));
                }
            }
        }
        crossings.extend((0..30).map(|k| DVec2::new(5.0 + 0.01 * k as f64, 0.0)));
        let seen = SeeThrough { points: vec![0], crossings, sight_lines: Vec::new() };
        let b = seen.region(0.1).expect("a region");
        // The crossings' box (2.95 x 0.45) and half a cell on each side.
        assert!((b.width - 3.05).abs() < 1e-9 && (b.height - 0.55).abs() < 1e-9, "{b:?}");
    }

    #[test]
    fn the_region_leaves_out_the_few_crossings_over_a_frame_around_the_pane() {
        // A 1 x 0.5 pane crossed densely (25 crossings a cell of 0.1), in a frame 0.15 wide
        // whose sampling gaps a few sight lines cross (4 a cell), touching the pane's crossings.
        let mut crossings = Vec::new();
        for iy in -15..65 {
            for ix in -15..115 {
                let q = DVec2::new(ix as f64 * 0.01 + 0.005, iy as f64 * 0.01 + 0.005);
                let in_pane = (0.0..1.0).contains(&q.x) && (0.0..0.5).contains(&q.y);
                let every = if in_pane { 2 } else { 5 };
                if ix % every == 0 && iy % every == 0 {
                    crossings.push(q);
                }
            }
        }
        let seen = SeeThrough { points: vec![0], crossings, sight_lines: Vec::new() };
        let b = seen.region(0.1).expect("a region");
        // The pane's crossings span 0.99 x 0.49; half a cell more on each side.
        assert!((1.05..1.1).contains(&b.width) && (0.55..0.6).contains(&b.height), "{b:?}");
        assert!(b.centre.distance(DVec2::new(0.5, 0.25)) < 0.01, "{b:?}");
    }

    #[test]
    fn the_region_is_the_box_of_the_crossings_without_strays() {
        let mut crossings = Vec::new();
        for iy in 0..10 {
            for ix in 0..20 {
                crossings.push(DVec2::new(ix as f64 * 0.05, iy as f64 * 0.05));
            }
        }
        crossings.push(DVec2::new(5.0, 5.0));
        let seen = SeeThrough { points: vec![0], crossings, sight_lines: Vec::new() };
        let b = seen.region(0.1).expect("a region");
        assert!((b.width - 1.05).abs() < 1e-9 && (b.height - 0.55).abs() < 1e-9, "{b:?}");
    }
}
