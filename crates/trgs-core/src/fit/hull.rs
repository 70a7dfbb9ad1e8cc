//! 2D convex hull (Andrew's monotone chain) and the minimum-area enclosing rectangle.
use glam::DVec2;

/// The convex hull of `points`, counter-clockwise, starting at the point with the smallest x
/// (smallest y on ties), without repeated or collinear vertices. Non-finite points are ignored.
///
/// Degenerate input gives a degenerate hull: no points → empty, all points equal → that one point,
/// all points collinear → the two extreme points.
pub fn convex_hull(points: &[DVec2]) -> Vec<DVec2> {
    let mut p: Vec<DVec2> = points.iter().copied().filter(|q| q.is_finite()).collect();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    // Lower chain left to right, then upper chain right to left. Popping on a non-left turn
    // (cross <= 0) drops collinear vertices as well as reflex ones.
    let mut hull: Vec<DVec2> = Vec::with_capacity(2 * p.len());
    for &q in &p {
        while hull.len() >= 2 && turn(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0 {
            hull.pop();
        }
        hull.push(q);
    }
    let lower_len = hull.len() + 1;
    for &q in p.iter().rev().skip(1) {
        while hull.len() >= lower_len && turn(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
        {
            hull.pop();
        }
        hull.push(q);
    }
    // The last vertex is the first one again.
    hull.pop();
    if hull.len() == 2 && hull[0] == hull[1] {
        hull.pop();
    }
    hull
}

/// z of (b - a) x (c - a): positive for a left (counter-clockwise) turn.
fn turn(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// A rectangle in the plane: `centre`, unit `axis` along the `width` side, `height` along
/// `axis.perp()`.
///
/// Convention of [`min_area_box`]: `width >= height`, and the sign of `axis` is fixed so that
/// `axis.x > 0`, or `axis.y > 0` when `axis.x == 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrientedBox {
    pub centre: DVec2,
    pub axis: DVec2,
    pub width: f64,
    pub height: f64,
}

impl OrientedBox {
    pub fn area(&self) -> f64 {
        self.width * self.height
    }

    /// The unit direction of the height side, `axis` rotated by +90 degrees.
    pub fn height_axis(&self) -> DVec2 {
        self.axis.perp()
    }

    /// The four corners, counter-clockwise.
    pub fn corners(&self) -> [DVec2; 4] {
        let (u, v) = (self.axis * (0.5 * self.width), self.height_axis() * (0.5 * self.height));
        let c = self.centre;
        [c - u - v, c + u - v, c + u + v, c - u + v]
    }

    /// Whether `p` is inside or within `tol` of the box.
    pub fn contains(&self, p: DVec2, tol: f64) -> bool {
        let d = p - self.centre;
        d.dot(self.axis).abs() <= 0.5 * self.width + tol
            && d.dot(self.height_axis()).abs() <= 0.5 * self.height + tol
    }
}

/// The minimum-area rectangle enclosing `points`: the optimal rectangle has a side collinear
/// with an edge of the convex hull, so each hull edge is tried.
///
/// Returns `None` when there is no finite point. Degenerate input is answered with a degenerate
/// box rather than `None`, so that callers can decide what is too thin: a single distinct point
/// gives `width == height == 0` with `axis = +x`; collinear points give `height == 0` and the
/// segment's length and direction. See [`OrientedBox`] for the width/axis convention.
pub fn min_area_box(points: &[DVec2]) -> Option<OrientedBox> {
    let hull = convex_hull(points);
    match hull.len() {
        0 => return None,
        1 => {
            return Some(OrientedBox { centre: hull[0], axis: DVec2::X, width: 0.0, height: 0.0 });
        }
        2 => {
            let d = hull[1] - hull[0];
            return Some(canonical(0.5 * (hull[0] + hull[1]), d.normalize(), d.length(), 0.0));
        }
        _ => {}
    }
    // Every hull edge is scored against every hull vertex: quadratic in the hull's size, which
    // stays at tens of vertices for the point sets fitted here. Rotating calipers (linear) once
    // stood here and returned a box leaving vertices outside on a real hull (the test
    // `min_area_box_of_a_pane_crossings_hull`).
    let mut best: Option<(f64, OrientedBox)> = None;
    for (i, &origin) in hull.iter().enumerate() {
        let e = (hull[(i + 1) % hull.len()] - origin).normalize();
        let nrm = e.perp();
        let (mut lo, mut hi, mut down, mut up) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for &q in &hull {
            let (a, b) = ((q - origin).dot(e), (q - origin).dot(nrm));
            (lo, hi, down, up) = (lo.min(a), hi.max(a), down.min(b), up.max(b));
        }
        let area = (hi - lo) * (up - down);
        if best.as_ref().is_none_or(|(a, _)| area < *a) {
            let centre = origin + e * (0.5 * (lo + hi)) + nrm * (0.5 * (down + up));
            best = Some((area, OrientedBox { centre, axis: e, width: hi - lo, height: up - down }));
        }
    }
    let (_, b) = best?;
    Some(canonical(b.centre, b.axis, b.width, b.height))
}

/// Apply the [`OrientedBox`] convention: the longer side is the width, and the axis sign is fixed.
fn canonical(centre: DVec2, axis: DVec2, width: f64, height: f64) -> OrientedBox {
    let (mut axis, width, height) =
        if height > width { (axis.perp(), height, width) } else { (axis, width, height) };
    if axis.x < 0.0 || (axis.x == 0.0 && axis.y < 0.0) {
        axis = -axis;
    }
    OrientedBox { centre, axis, width, height }
}
