//! Planar structures of a point cloud (walls, facades, floors), found without masks for the plane
//! proposal ([`super::propose_planes`]): sequential RANSAC, each plane's inliers split into
//! connected pieces in the plane, and near-coplanar pieces merged again (a wall that RANSAC split
//! into two thin slabs, or a facade whose panes RANSAC found one by one, is one structure).
use glam::{DVec2, DVec3};
use std::collections::{HashMap, HashSet};

use super::hull::convex_hull;
use super::ransac::{least_squares_plane, ransac_plane};
use crate::rng::Rng;

/// A planar structure: a plane and the points on it.
#[derive(Clone, Debug, PartialEq)]
pub struct Structure {
    /// A point on the plane: the centroid of the inliers.
    pub point: DVec3,
    /// Unit normal, sign arbitrary.
    pub normal: DVec3,
    /// In-plane orthonormal basis `(u, v)` with `u x v = normal`.
    pub basis: (DVec3, DVec3),
    /// Indices of the points on the structure.
    pub inliers: Vec<usize>,
    /// The convex hull of the inliers in plane coordinates, counter-clockwise.
    pub hull: Vec<DVec2>,
    /// The side of the occupancy grid: about [`POINTS_PER_CELL`] inliers per cell of the hull
    /// on average, so that a wall's sampling gaps are not holes while a pane is.
    pub occupancy_cell: f64,
    /// The grid cells that hold inliers.
    pub occupied: HashSet<(i64, i64)>,
}

/// Inliers per occupancy cell of a structure, on average over its hull.
pub const POINTS_PER_CELL: f64 = 4.0;

impl Structure {
    /// A structure from its inliers: the least-squares plane and hull. `None` when they span no
    /// plane.
    pub fn from_inliers(points: &[DVec3], inliers: Vec<usize>) -> Option<Self> {
        let (point, normal) = least_squares_plane(points, &inliers)?;
        Some(Self::with_plane(points, point, normal, inliers))
    }

    fn with_plane(points: &[DVec3], point: DVec3, normal: DVec3, inliers: Vec<usize>) -> Self {
        let u = normal.any_orthonormal_vector();
        let v = normal.cross(u);
        let mut s = Self {
            point,
            normal,
            basis: (u, v),
            inliers,
            hull: Vec::new(),
            occupancy_cell: 0.0,
            occupied: HashSet::new(),
        };
        let flat: Vec<DVec2> = s.inliers.iter().map(|&i| s.to_plane(points[i])).collect();
        s.hull = convex_hull(&flat);
        let area = polygon_area(&s.hull);
        s.occupancy_cell = (POINTS_PER_CELL * area / flat.len().max(1) as f64).sqrt();
        if s.occupancy_cell > 0.0 {
            s.occupied = flat.iter().map(|&q| s.cell_of(q)).collect();
        }
        s
    }

    fn cell_of(&self, q: DVec2) -> (i64, i64) {
        grid_cell(q, self.occupancy_cell)
    }

    /// Whether plane coordinates `q` fall in a hole of the structure: inside its hull, in an
    /// occupancy cell that holds none of its points (where a sight line can pass through it).
    pub fn is_hole(&self, q: DVec2) -> bool {
        self.occupancy_cell > 0.0
            && self.hull_contains(q, 0.0)
            && !self.occupied.contains(&self.cell_of(q))
    }

    /// Whether plane coordinates `q` fall on the structure: in an occupancy cell that holds some
    /// of its points, where a sight line is blocked.
    pub fn blocks(&self, q: DVec2) -> bool {
        self.occupancy_cell > 0.0 && self.occupied.contains(&self.cell_of(q))
    }

    /// Plane coordinates of `p` (its projection onto the plane).
    pub fn to_plane(&self, p: DVec3) -> DVec2 {
        let d = p - self.point;
        DVec2::new(d.dot(self.basis.0), d.dot(self.basis.1))
    }

    /// The world point of plane coordinates `q`.
    pub fn to_world(&self, q: DVec2) -> DVec3 {
        self.point + self.basis.0 * q.x + self.basis.1 * q.y
    }

    /// Signed distance of `p` from the plane along `normal`.
    pub fn signed_distance(&self, p: DVec3) -> f64 {
        (p - self.point).dot(self.normal)
    }

    /// Whether plane coordinates `q` lie inside the hull grown by `margin`.
    pub fn hull_contains(&self, q: DVec2, margin: f64) -> bool {
        inside_convex(&self.hull, q, margin)
    }
}

/// How structures are searched.
#[derive(Clone, Debug, PartialEq)]
pub struct StructureSettings {
    /// Inlier distance, in scene units.
    pub threshold: f64,
    pub ransac_iterations: usize,
    /// RANSAC scores its hypotheses on at most this many points (an even subsample); inliers are
    /// then taken from all points.
    pub ransac_sample: usize,
    /// At most this many RANSAC planes are searched.
    pub max_planes: usize,
    /// A piece needs at least this many points to be a structure.
    pub min_support: usize,
    /// Grid cell for the connected pieces of a plane's inliers, in scene units.
    pub cell: f64,
    /// Pieces whose normals are within this angle (degrees), each one's centroid within
    /// `merge_offset` of the other's plane, and whose hulls touch are merged.
    pub merge_angle_deg: f64,
    pub merge_offset: f64,
}

/// The planar structures of `points`, the best-supported first.
pub fn find_structures(
    points: &[DVec3],
    settings: &StructureSettings,
    rng: &mut Rng,
) -> Vec<Structure> {
    let mut remaining: Vec<usize> = (0..points.len()).collect();
    let mut found = Vec::new();
    for _ in 0..settings.max_planes {
        if remaining.len() < settings.min_support.max(3) {
            break;
        }
        let stride = remaining.len().div_ceil(settings.ransac_sample.max(3));
        let sample: Vec<DVec3> = remaining.iter().step_by(stride).map(|&i| points[i]).collect();
        let Some(fit) = ransac_plane(&sample, settings.threshold, settings.ransac_iterations, rng)
        else {
            break;
        };
        let on = |i: usize| (points[i] - fit.point).dot(fit.normal).abs() <= settings.threshold;
        let inliers: Vec<usize> = remaining.iter().copied().filter(|&i| on(i)).collect();
        if inliers.len() < settings.min_support {
            break;
        }
        // The plane's points leave the search whether or not a piece of them is kept: small
        // pieces of a found plane are not worth a plane of their own.
        remaining.retain(|&i| !on(i));
        let plane = Structure::with_plane(points, fit.point, fit.normal, inliers);
        for piece in connected_pieces(points, &plane, settings.cell) {
            if piece.len() >= settings.min_support {
                found.extend(Structure::from_inliers(points, piece));
            }
        }
    }
    let mut merged = merge_coplanar(points, found, settings);
    merged.sort_by_key(|s| std::cmp::Reverse(s.inliers.len()));
    merged
}

/// The inliers of `plane` split into pieces connected on a grid of `cell`, the largest first.
fn connected_pieces(points: &[DVec3], plane: &Structure, cell: f64) -> Vec<Vec<usize>> {
    let flat: Vec<DVec2> = plane.inliers.iter().map(|&i| plane.to_plane(points[i])).collect();
    grid_components(&flat, cell)
        .into_iter()
        .map(|piece| piece.into_iter().map(|k| plane.inliers[k]).collect())
        .collect()
}

/// The cell of a square grid of side `cell` (origin at the plane's origin) that holds `q`.
pub(super) fn grid_cell(q: DVec2, cell: f64) -> (i64, i64) {
    let c = q / cell;
    (c.x.floor() as i64, c.y.floor() as i64)
}

/// The indices of `coords` grouped by the 8-connected components of the grid cells of size
/// `cell` they occupy, the largest group first (ties: the component met first in cell order),
/// each group ascending.
pub(super) fn grid_components(coords: &[DVec2], cell: f64) -> Vec<Vec<usize>> {
    let mut cells: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (k, q) in coords.iter().enumerate() {
        cells.entry(grid_cell(*q, cell)).or_default().push(k);
    }
    let mut keys: Vec<(i64, i64)> = cells.keys().copied().collect();
    keys.sort_unstable();
    let mut piece_of: HashMap<(i64, i64), usize> = HashMap::new();
    let mut pieces: Vec<Vec<usize>> = Vec::new();
    for start in keys {
        if piece_of.contains_key(&start) {
            continue;
        }
        let id = pieces.len();
        let mut members = Vec::new();
        let mut stack = vec![start];
        piece_of.insert(start, id);
        while let Some(c) = stack.pop() {
            members.extend_from_slice(&cells[&c]);
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let n = (c.0 + dx, c.1 + dy);
                    if cells.contains_key(&n) && !piece_of.contains_key(&n) {
                        piece_of.insert(n, id);
                        stack.push(n);
                    }
                }
            }
        }
        members.sort_unstable();
        pieces.push(members);
    }
    // A stable sort keeps the cell order among pieces of one size.
    pieces.sort_by_key(|p| std::cmp::Reverse(p.len()));
    pieces
}

/// Merge structures that are one plane: normals within the angle, each one's centroid within the
/// offset of the other's plane, and hulls that touch (within one grid cell).
fn merge_coplanar(
    points: &[DVec3],
    mut structures: Vec<Structure>,
    settings: &StructureSettings,
) -> Vec<Structure> {
    let cos_max = settings.merge_angle_deg.to_radians().cos();
    let same = |a: &Structure, b: &Structure| {
        a.normal.dot(b.normal).abs() >= cos_max
            && a.signed_distance(b.point).abs() <= settings.merge_offset
            && b.signed_distance(a.point).abs() <= settings.merge_offset
            && hulls_touch(a, b, settings.cell)
    };
    loop {
        let pair = (0..structures.len()).find_map(|i| {
            (i + 1..structures.len())
                .find(|&j| same(&structures[i], &structures[j]))
                .map(|j| (i, j))
        });
        let Some((i, j)) = pair else { return structures };
        let b = structures.swap_remove(j);
        let a = structures.swap_remove(i);
        let mut inliers = [a.inliers.as_slice(), b.inliers.as_slice()].concat();
        inliers.sort_unstable();
        inliers.dedup();
        match Structure::from_inliers(points, inliers) {
            Some(s) => structures.push(s),
            // Two planes that merge into no plane cannot happen for coplanar pieces; keep both.
            None => structures.extend([a, b]),
        }
    }
}

/// Whether the hulls of two (nearly coplanar) structures overlap or come within `gap`, tested in
/// `a`'s plane: a vertex of one inside the other grown by `gap`.
pub(super) fn hulls_touch(a: &Structure, b: &Structure, gap: f64) -> bool {
    let mut b_in_a: Vec<DVec2> = b.hull.iter().map(|&q| a.to_plane(b.to_world(q))).collect();
    // Normals that point opposite ways (their signs are arbitrary) mirror b's hull in a's plane:
    // `inside_convex` needs it counter-clockwise again.
    if polygon_area(&b_in_a) < 0.0 {
        b_in_a.reverse();
    }
    b_in_a.iter().any(|&q| inside_convex(&a.hull, q, gap))
        || a.hull.iter().any(|&q| inside_convex(&b_in_a, q, gap))
        || edges_cross(&a.hull, &b_in_a)
}

/// The area of a counter-clockwise polygon (0 for fewer than 3 vertices).
pub(super) fn polygon_area(p: &[DVec2]) -> f64 {
    if p.len() < 3 {
        return 0.0;
    }
    0.5 * (0..p.len()).map(|k| p[k].perp_dot(p[(k + 1) % p.len()])).sum::<f64>()
}

/// Whether `q` lies inside the counter-clockwise convex polygon `hull` grown by `margin` (its
/// distance outside every edge line at most `margin`). Degenerate hulls (a point, a segment)
/// contain what lies within `margin` of them.
pub fn inside_convex(hull: &[DVec2], q: DVec2, margin: f64) -> bool {
    match hull.len() {
        0 => false,
        1 => q.distance(hull[0]) <= margin,
        2 => segment_distance(hull[0], hull[1], q) <= margin,
        n => (0..n).all(|k| {
            let (a, b) = (hull[k], hull[(k + 1) % n]);
            let e = b - a;
            // Outward distance of q from the edge line (the hull is counter-clockwise).
            -(e.perp_dot(q - a)) / e.length() <= margin
        }),
    }
}

fn segment_distance(a: DVec2, b: DVec2, q: DVec2) -> f64 {
    let e = b - a;
    let t = if e.length_squared() > 0.0 {
        ((q - a).dot(e) / e.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    q.distance(a + e * t)
}

/// Whether an edge of polygon `a` properly crosses an edge of polygon `b` (two convex polygons
/// that overlap without either holding a vertex of the other, like a cross).
fn edges_cross(a: &[DVec2], b: &[DVec2]) -> bool {
    let edges = |p: &[DVec2]| -> Vec<(DVec2, DVec2)> {
        (0..p.len()).map(|k| (p[k], p[(k + 1) % p.len()])).collect()
    };
    let side = |a: DVec2, b: DVec2, c: DVec2| (b - a).perp_dot(c - a);
    edges(a).iter().any(|&(p, q)| {
        edges(b).iter().any(|&(r, s)| {
            side(p, q, r) * side(p, q, s) < 0.0 && side(r, s, p) * side(r, s, q) < 0.0
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings() -> StructureSettings {
        StructureSettings {
            threshold: 0.01,
            ransac_iterations: 500,
            ransac_sample: 4000,
            max_planes: 6,
            min_support: 50,
            cell: 0.1,
            merge_angle_deg: 2.0,
            merge_offset: 0.03,
        }
    }

    /// A grid of points on the rectangle [x0, x1] x [y0, y1] at z = `z`, jittered by `noise`.
    fn wall(
        x: (f64, f64),
        y: (f64, f64),
        z: f64,
        step: f64,
        noise: f64,
        rng: &mut Rng,
    ) -> Vec<DVec3> {
        let mut out = Vec::new();
        let mut py = y.0;
        while py <= y.1 {
            let mut px = x.0;
            while px <= x.1 {
                out.push(DVec3::new(px, py, z + noise * (2.0 * rng.uniform() - 1.0)));
                px += step;
            }
            py += step;
        }
        out
    }

    #[test]
    fn two_walls_and_clutter_give_two_structures() {
        let mut rng = Rng::new(7);
        let mut points = wall((-1.0, 1.0), (0.0, 1.0), 0.0, 0.04, 0.002, &mut rng);
        // A floor, turned 90 degrees: y = 0, z in [0, 1].
        let floor: Vec<DVec3> = wall((-1.0, 1.0), (0.0, 1.0), 0.0, 0.05, 0.002, &mut rng)
            .into_iter()
            .map(|p| DVec3::new(p.x, p.z, p.y + 0.05))
            .collect();
        points.extend(floor);
        for _ in 0..200 {
            points.push(DVec3::new(rng.range(-1.0, 1.0), rng.range(0.1, 1.0), rng.range(0.1, 1.0)));
        }
        let found = find_structures(&points, &settings(), &mut rng);
        assert_eq!(
            found.len(),
            2,
            "{:?}",
            found.iter().map(|s| s.inliers.len()).collect::<Vec<_>>()
        );
        assert!(
            found[0].normal.z.abs() > 0.999,
            "the wall first (more points): {}",
            found[0].normal
        );
        assert!(found[1].normal.y.abs() > 0.999, "then the floor: {}", found[1].normal);
    }

    #[test]
    fn separate_panels_in_one_plane_are_separate_pieces_and_a_split_wall_is_merged() {
        let mut rng = Rng::new(3);
        // Two panels 0.5 apart in z = 0: separate structures.
        let mut points = wall((-1.0, -0.3), (0.0, 1.0), 0.0, 0.04, 0.0, &mut rng);
        points.extend(wall((0.3, 1.0), (0.0, 1.0), 0.0, 0.04, 0.0, &mut rng));
        let found = find_structures(&points, &settings(), &mut rng);
        assert_eq!(found.len(), 2);
        // A thick wall (noise 3x the threshold): RANSAC takes it in slabs, the merge rejoins them.
        let thick = wall((-1.0, 1.0), (0.0, 1.0), 0.0, 0.03, 0.03, &mut rng);
        let found = find_structures(&thick, &settings(), &mut rng);
        assert_eq!(
            found.len(),
            1,
            "{:?}",
            found.iter().map(|s| s.inliers.len()).collect::<Vec<_>>()
        );
        assert!(found[0].inliers.len() as f64 > 0.9 * thick.len() as f64);
    }

    #[test]
    fn hulls_touch_whichever_way_their_normals_point() {
        // A small piece inside a large one of the same plane, the large one's normal flipped.
        let grid = |half: f64| -> Vec<DVec3> {
            (0..=4)
                .flat_map(|i| (0..=4).map(move |j| (i, j)))
                .map(|(i, j)| {
                    DVec3::new(half * (i as f64 / 2.0 - 1.0), half * (j as f64 / 2.0 - 1.0), 0.0)
                })
                .collect()
        };
        let (small, large) = (grid(0.5), grid(3.0));
        let all: Vec<usize> = (0..small.len()).collect();
        let a = Structure::with_plane(&small, DVec3::ZERO, DVec3::Z, all.clone());
        for normal in [DVec3::Z, -DVec3::Z] {
            let b = Structure::with_plane(&large, DVec3::ZERO, normal, all.clone());
            assert!(hulls_touch(&a, &b, 0.01) && hulls_touch(&b, &a, 0.01), "normal {normal}");
        }
        let far: Vec<DVec3> = large.iter().map(|p| *p + DVec3::X * 10.0).collect();
        let c = Structure::with_plane(&far, DVec3::X * 10.0, -DVec3::Z, all);
        assert!(!hulls_touch(&a, &c, 0.01) && !hulls_touch(&c, &a, 0.01));
    }

    #[test]
    fn convex_containment_with_margin() {
        let square = [DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
        assert!(inside_convex(&square, DVec2::splat(0.5), 0.0));
        assert!(!inside_convex(&square, DVec2::new(1.2, 0.5), 0.1));
        assert!(inside_convex(&square, DVec2::new(1.05, 0.5), 0.1));
        assert!(inside_convex(&[DVec2::ZERO, DVec2::X], DVec2::new(0.5, 0.05), 0.1));
        assert!(!inside_convex(&[], DVec2::ZERO, 1.0));
    }
}
