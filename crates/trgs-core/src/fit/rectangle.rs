//! Rectangle fitting (RANSAC plane, then the minimum-area box of the inliers in that plane), and
//! uniform sampling of a rectangle for the glass Gaussians.
use glam::{DVec2, DVec3};

use super::hull::min_area_box;
use super::ransac::ransac_plane;
use crate::rng::Rng;
use crate::scene::{Material, ReflectionPlane};

/// A rectangle fitted to a point cloud.
#[derive(Clone, Debug, PartialEq)]
pub struct RectangleFit {
    /// The centre of the minimum-area box, lifted back to 3D. Not the inlier centroid: points near
    /// a glass pane's edges come from a band around the mask outline, so the centroid leans toward
    /// whichever edges contributed more points, while the box centre depends only on the extremes.
    pub centre: DVec3,
    /// Unit normal; the sign is RANSAC's arbitrary one (see [`super::orient_towards`]).
    pub normal: DVec3,
    /// Unit, in-plane, along the width. Its sign follows an arbitrary in-plane basis: a rectangle
    /// is symmetric under `axis -> -axis`, so nothing downstream depends on it.
    pub axis: DVec3,
    /// The longer side of the box.
    pub width: f64,
    /// The shorter side of the box.
    pub height: f64,
    /// Indices of the input points within the RANSAC threshold of the refined plane.
    pub inliers: Vec<usize>,
}

impl RectangleFit {
    /// The reflection plane this fit initialises, with the material's initial reflectance. Orient
    /// `normal` first ([`super::orient_towards`]): the plane's front side is where it points.
    pub fn to_plane(&self, material: Material) -> ReflectionPlane {
        ReflectionPlane::new(self.centre, self.normal, self.axis, self.width, self.height, material)
    }
}

/// Fit a rectangle to `points`: [`ransac_plane`] with `threshold` and `iterations`, the inliers
/// projected into the plane, and their minimum-area enclosing box ([`min_area_box`]).
///
/// Returns `None` when RANSAC finds no plane or the inliers span no area in it (zero width or
/// height: a reflection plane must have a positive area).
pub fn fit_rectangle(
    points: &[DVec3],
    threshold: f64,
    iterations: usize,
    rng: &mut Rng,
) -> Option<RectangleFit> {
    let fit = ransac_plane(points, threshold, iterations, rng)?;
    let normal = fit.normal;
    // Any orthonormal in-plane basis will do: the box is found in it, then mapped back.
    let u = normal.any_orthonormal_vector();
    let v = normal.cross(u);
    let projected: Vec<DVec2> = fit
        .inliers
        .iter()
        .map(|&i| {
            let d = points[i] - fit.point;
            DVec2::new(d.dot(u), d.dot(v))
        })
        .collect();
    let b = min_area_box(&projected)?;
    if !(b.width > 0.0 && b.height > 0.0) {
        return None;
    }
    Some(RectangleFit {
        centre: fit.point + u * b.centre.x + v * b.centre.y,
        normal,
        axis: (u * b.axis.x + v * b.axis.y).normalize(),
        width: b.width,
        height: b.height,
        inliers: fit.inliers,
    })
}

/// Exactly `n` points uniformly distributed on `plane`'s rectangle, by a jittered stratified grid:
/// about `n` cells of roughly square shape, one uniform point in each of `n` cells chosen at random
/// when the grid has a few more cells than `n`. Every point is inside the rectangle (boundary
/// included). The points come in row-major cell order (rows along the height axis).
pub fn sample_rectangle(plane: &ReflectionPlane, n: usize, rng: &mut Rng) -> Vec<DVec3> {
    if n == 0 {
        return Vec::new();
    }
    let (w, h) = (plane.width, plane.height);
    // Columns along the width so that cells are about square: nx / ny ~ w / h and nx * ny ~ n.
    let aspect = w / h;
    let aspect = if aspect.is_finite() && aspect > 0.0 { aspect } else { 1.0 };
    let nx = ((n as f64 * aspect).sqrt().round() as usize).clamp(1, n);
    let ny = n.div_ceil(nx);
    let cells = nx * ny;
    // Choose n distinct cells by a partial Fisher-Yates shuffle; cells - n < nx, so only a few
    // cells go empty, and which ones is random so no edge is systematically thinned.
    let mut ids: Vec<usize> = (0..cells).collect();
    for i in 0..n {
        let j = i + rng.below(cells - i);
        ids.swap(i, j);
    }
    ids.truncate(n);
    ids.sort_unstable();
    let (t, b) = (plane.axis, plane.bitangent());
    let corner = plane.centre - t * (0.5 * w) - b * (0.5 * h);
    ids.into_iter()
        .map(|id| {
            let (ix, iy) = (id % nx, id / nx);
            // uniform() < 1, so the fractions stay in [0, 1) and the points inside the rectangle.
            let fx = (ix as f64 + rng.uniform()) / nx as f64;
            let fy = (iy as f64 + rng.uniform()) / ny as f64;
            corner + t * (fx * w) + b * (fy * h)
        })
        .collect()
}
