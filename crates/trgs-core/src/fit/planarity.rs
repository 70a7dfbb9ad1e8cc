//! How flat a planar structure is, the proposal's test that it is a surface and not a slice
//! through a cloud of points (`super::propose`): of the points near its plane, the share that
//! lies on it, over its hull and over the cells of its plane it holds points in. The second
//! leaves out what is seen through the structure's holes: the room a plain model grows right
//! behind a mirror lies within a few thresholds of the wall around it.
use glam::DVec3;

use super::structures::Structure;

/// How many thresholds from a plane count as near it for both shares of [`planarity`].
pub const PLANARITY_SLAB: f64 = 4.0;

/// Of the points within [`PLANARITY_SLAB`] thresholds of `s`'s plane inside its hull, the share
/// within one `threshold`; and the same share over the cells of the plane that hold points of
/// `s` ([`Structure::blocks`]). 0 where no point is near.
pub fn planarity(s: &Structure, points: &[DVec3], threshold: f64) -> (f64, f64) {
    let (mut near, mut on, mut near_wall, mut on_wall) = (0usize, 0usize, 0usize, 0usize);
    for &p in points {
        let d = s.signed_distance(p).abs();
        let q = s.to_plane(p);
        if d <= PLANARITY_SLAB * threshold && s.hull_contains(q, 0.0) {
            let flat = usize::from(d <= threshold);
            near += 1;
            on += flat;
            if s.blocks(q) {
                near_wall += 1;
                on_wall += flat;
            }
        }
    }
    let share = |on: usize, near: usize| if near == 0 { 0.0 } else { on as f64 / near as f64 };
    (share(on, near), share(on_wall, near_wall))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn the_room_grown_right_behind_a_mirror_lowers_its_planarity_but_not_its_walls() {
        // A wall in z = 0 over [-3, 3] x [0, 2.8] with a 1 x 1 hole, and twice as many points
        // as the wall holds over the hole, 1.3 to 3.8 thresholds behind it.
        let mut points = Vec::new();
        for j in 0..=56 {
            for i in 0..=120 {
                let (x, y) = (-3.0 + 0.05 * f64::from(i), 0.05 * f64::from(j));
                if !((-0.5..0.5).contains(&x) && (0.5..1.5).contains(&y)) {
                    points.push(DVec3::new(x, y, 0.0));
                }
            }
        }
        let wall: Vec<usize> = (0..points.len()).collect();
        let mut rng = Rng::new(7);
        points.extend((0..13_000).map(|_| {
            DVec3::new(rng.range(-0.5, 0.5), rng.range(0.5, 1.5), rng.range(-0.115, -0.04))
        }));
        let s = Structure::from_inliers(&points, wall).expect("the wall");
        let (flat, wall_flat) = planarity(&s, &points, 0.03);
        assert!(flat < 0.4, "{flat}");
        // The cells along the hole's edge hold both the wall's points and some of the room's.
        assert!(wall_flat >= 0.5, "{wall_flat}");
        // A slice through a cloud: three times as many points near it off it as on it, over its
        // own cells too.
        let mut rng = Rng::new(3);
        let cloud: Vec<DVec3> = (0..20_000)
            .map(|_| DVec3::new(rng.uniform(), rng.uniform(), 0.24 * rng.uniform() - 0.12))
            .collect();
        let slice: Vec<usize> = (0..cloud.len()).filter(|&i| cloud[i].z.abs() <= 0.03).collect();
        let s = Structure::from_inliers(&cloud, slice).expect("a slice");
        let (flat, wall_flat) = planarity(&s, &cloud, 0.03);
        assert!(flat < 0.4 && wall_flat < 0.4, "{flat} {wall_flat}");
    }
}
