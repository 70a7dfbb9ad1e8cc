//! Unit tests of `fit::propose`: rooms of points with panes, mirrors and openings, and the
//! candidates proposed over them.
use super::*;
use crate::scene::{Intrinsics, Pose};

/// Points on a grid of `step` over `[x0, x1] x [y0, y1]`, mapped to 3D by `at`.
pub(in crate::fit) fn grid(
    x: (f64, f64),
    y: (f64, f64),
    step: f64,
    at: impl Fn(f64, f64) -> DVec3,
) -> Vec<DVec3> {
    let (nx, ny) = (((x.1 - x.0) / step).round() as usize, ((y.1 - y.0) / step).round() as usize);
    (0..=ny)
        .flat_map(|j| (0..=nx).map(move |i| (x.0 + i as f64 * step, y.0 + j as f64 * step)))
        .map(|(a, b)| at(a, b))
        .collect()
}

/// A room: a wall in z = 0 over [-3, 3] x [0, 2.8], a floor, and cameras at z = 3 looking at
/// the wall; the wall has holes (panes) over each x range of `panes` with y in [0.5, 1.5],
/// and two layers of points behind them, where the cameras see them through the holes.
fn room(panes: &[(f64, f64)]) -> (Vec<DVec3>, Vec<Camera>) {
    let hole =
        |x: f64, y: f64| panes.iter().any(|&(a, b)| (a..b).contains(&x)) && (0.5..1.5).contains(&y);
    let mut points: Vec<DVec3> = grid((-3.0, 3.0), (0.0, 2.8), 0.05, |x, y| DVec3::new(x, y, 0.0))
        .into_iter()
        .filter(|p| !hole(p.x, p.y))
        .collect();
    points.extend(grid((-3.0, 3.0), (0.1, 3.0), 0.05, |x, z| DVec3::new(x, 0.0, z)));
    if let (Some(left), Some(right)) = (panes.first(), panes.last()) {
        let x = (left.0 - 0.1, right.1 + 0.1);
        for z in [-0.5, -1.5] {
            points.extend(grid(x, (0.4, 1.6), 0.025, |x, y| DVec3::new(x, y, z)));
        }
    }
    let k = Intrinsics::from_fov_x(1.2, 64, 48);
    let cameras = [-0.5, 0.0, 0.5]
        .iter()
        .flat_map(|&x| [0.8, 1.2].map(|y| DVec3::new(x, y, 3.0)))
        .map(|eye| Camera::new("c", k, Pose::look_at(eye, DVec3::new(0.0, 1.0, 0.0), DVec3::Y)))
        .collect();
    (points, cameras)
}

/// The proposal's candidates with the default settings.
fn candidates(points: &[DVec3], cameras: &[Camera]) -> Vec<PlaneCandidate> {
    propose_planes(points, cameras, &ProposalSettings::default(), &mut Rng::new(1)).candidates
}

#[test]
fn a_window_in_a_wall_is_the_one_candidate_and_spans_the_hole() {
    let (points, cameras) = room(&[(-0.5, 0.5)]);
    let found = candidates(&points, &cameras);
    let proposed: Vec<_> = found.iter().filter(|c| c.rejected.is_none()).collect();
    assert_eq!(proposed.len(), 1, "{found:#?}");
    let plane = proposed[0].plane.expect("a plane");
    assert!(plane.unit_normal().dot(DVec3::Z) > 0.9998, "normal toward the cameras: {plane:?}");
    assert!(plane.centre.distance(DVec3::new(0.0, 1.0, 0.0)) < 0.1, "{plane:?}");
    assert!((0.8..1.5).contains(&plane.width) && (0.8..1.5).contains(&plane.height), "{plane:?}");
    // The floor: no camera sees through it.
    assert!(found.iter().any(|c| c.rejected.is_some() && c.seen_through == 0));
}

#[test]
fn a_closed_room_gives_no_candidate() {
    let (points, cameras) = room(&[]);
    let found = candidates(&points, &cameras);
    assert!(!found.is_empty(), "the wall and floor are considered");
    assert!(found.iter().all(|c| c.rejected.is_some()), "{found:#?}");
}

/// The virtual room a plain model grows behind a mirror: points over the hole of
/// `room(&[(-0.5, 0.5)])`, 1.3 to 3.8 thresholds behind the wall (the depth scale is
/// about 3), twice as many as the wall holds.
fn mirrored_room_behind_the_glass() -> Vec<DVec3> {
    let mut rng = Rng::new(7);
    (0..13_000)
        .map(|_| DVec3::new(rng.range(-0.5, 0.5), rng.range(0.5, 1.5), rng.range(-0.115, -0.04)))
        .collect()
}

#[test]
fn a_mirror_whose_room_lies_right_behind_the_glass_is_proposed() {
    let (mut points, cameras) = room(&[(-0.5, 0.5)]);
    points.extend(mirrored_room_behind_the_glass());
    let found = candidates(&points, &cameras);
    let proposed: Vec<_> = found.iter().filter(|c| c.rejected.is_none()).collect();
    assert_eq!(proposed.len(), 1, "{found:#?}");
    let c = proposed[0];
    assert!(c.planarity < 0.4 && c.wall_planarity >= 0.5, "{c:#?}");
    let plane = c.plane.expect("a plane");
    assert!(plane.unit_normal().dot(DVec3::Z) > 0.9998, "{plane:?}");
    assert!(plane.centre.distance(DVec3::new(0.0, 1.0, 0.0)) < 0.1, "{plane:?}");
}

#[test]
fn a_facade_of_panes_between_mullions_is_one_candidate_over_all_of_them() {
    // Three panes 0.7 to 0.85 wide, split by mullions 0.3 wide: wider than the grid cell
    // that groups the sight lines' crossings, so each pane's crossings are a group of
    // their own.
    let panes = [(-1.5, -0.65), (-0.35, 0.35), (0.65, 1.5)];
    let (points, cameras) = room(&panes);
    let found = candidates(&points, &cameras);
    let proposed: Vec<_> = found.iter().filter(|c| c.rejected.is_none()).collect();
    assert_eq!(proposed.len(), 1, "{found:#?}");
    let plane = proposed[0].plane.expect("a plane");
    assert!(plane.unit_normal().dot(DVec3::Z) > 0.9998, "{plane:?}");
    let (width, height) = if plane.axis.x.abs() > plane.axis.y.abs() {
        (plane.width, plane.height)
    } else {
        (plane.height, plane.width)
    };
    assert!((2.7..3.3).contains(&width) && (0.8..1.3).contains(&height), "{plane:?}");
    assert!(plane.centre.distance(DVec3::new(0.0, 1.0, 0.0)) < 0.15, "{plane:?}");
}

/// The one candidate proposed for `room(&[(-0.5, 0.5)])`'s pane, checked to span its width.
fn the_one_pane_whole(points: &[DVec3], cameras: &[Camera]) -> ReflectionPlane {
    let found = candidates(points, cameras);
    let proposed: Vec<_> = found.iter().filter(|c| c.rejected.is_none()).collect();
    assert_eq!(proposed.len(), 1, "{found:#?}");
    let plane = proposed[0].plane.expect("a plane");
    let width = if plane.axis.x.abs() > plane.axis.y.abs() { plane.width } else { plane.height };
    assert!((0.9..1.3).contains(&width), "the whole pane: {plane:?}");
    plane
}

#[test]
fn a_pane_seen_through_two_pieces_of_wall_a_strip_apart_is_one_candidate() {
    // RANSAC's pieces of one wall 0.26 apart (wider than a grid cell) across the middle of
    // the pane: each piece's hull holds 0.37 of its width, and the strip between them
    // neither, so their see-through rectangles lie apart.
    let (mut points, cameras) = room(&[(-0.5, 0.5)]);
    points.retain(|p| p.z != 0.0 || p.x.abs() > 0.13);
    let plane = the_one_pane_whole(&points, &cameras);
    assert!(plane.centre.distance(DVec3::new(0.0, 1.0, 0.0)) < 0.1, "{plane:?}");
}

#[test]
fn a_pane_between_two_pieces_of_wall_that_do_not_touch_is_one_candidate_over_all_of_it() {
    // The wall right of x = 0.05 set 0.1 back, the left piece ending at x = -0.05: two
    // structures that do not touch, each with half the pane in its hull.
    let (mut points, cameras) = room(&[(-0.5, 0.5)]);
    points.retain(|p| p.z != 0.0 || p.x.abs() > 0.05);
    for p in points.iter_mut().filter(|p| p.z == 0.0 && p.x > 0.0) {
        p.z = -0.1;
    }
    let plane = the_one_pane_whole(&points, &cameras);
    let centre = plane.centre - DVec3::Z * plane.centre.z;
    assert!(centre.distance(DVec3::new(0.0, 1.0, 0.0)) < 0.1, "{plane:?}");
}

#[test]
fn a_pane_turned_in_its_opening_takes_that_opening_from_the_wall() {
    // Two openings; in the right one a pane turned 20 degrees about the opening's vertical
    // centre line, of which the cameras see the frame's left stile and the rails' left part.
    let (mut points, cameras) = room(&[(-1.5, -0.5), (0.5, 1.5)]);
    let (s, c) = (20f64.to_radians().sin(), 20f64.to_radians().cos());
    let turned = |u: f64, y: f64| DVec3::new(1.0 + u * c, y, -u * s);
    points.extend(grid((-0.5, -0.4), (0.5, 1.5), 0.02, turned));
    for y in [(0.5, 0.54), (1.46, 1.5)] {
        points.extend(grid((-0.38, 0.2), y, 0.02, turned));
    }
    let found = candidates(&points, &cameras);
    let proposed: Vec<_> = found.iter().filter(|c| c.rejected.is_none()).collect();
    let wall = proposed.iter().position(|c| c.opening_of.is_none());
    let wall = wall.unwrap_or_else(|| panic!("no wall: {found:#?}"));
    let pane = proposed.iter().find(|c| c.opening_of == Some(wall));
    let pane = pane.unwrap_or_else(|| panic!("no pane turned in an opening: {found:#?}"));
    let left = proposed[wall].plane.expect("a plane");
    assert!(left.unit_normal().dot(DVec3::Z) > 0.9998, "{left:?}");
    assert!(left.centre.distance(DVec3::new(-1.0, 1.0, 0.0)) < 0.1, "only its own: {left:?}");
    let right = pane.plane.expect("a plane");
    let normal = DVec3::new(s, 0.0, c);
    assert!(right.unit_normal().dot(normal) > 0.9998, "{right:?}");
    assert!(right.centre.distance(DVec3::new(1.0, 1.0, 0.0)) < 0.2, "{right:?}");
    assert!((0.9..1.4).contains(&right.width.max(right.height)), "{right:?}");
    // The opening it took, in the wall's plane.
    let opening = pane.opening.expect("its opening");
    assert!(opening.unit_normal().dot(DVec3::Z) > 0.9998, "{opening:?}");
    assert!(opening.centre.distance(DVec3::new(1.0, 1.0, 0.0)) < 0.1, "{opening:?}");
    let sides = [opening.width, opening.height];
    assert!(sides.iter().all(|w| (0.9..1.25).contains(w)), "{opening:?}");
    assert_eq!(proposed[wall].opening, None);
}
