//! RANSAC plane fitting with a least-squares (PCA) refinement, and normal orientation.
use glam::{DMat3, DVec3};

use crate::rng::Rng;

/// A plane through `point` with unit `normal`, and the indices of the input points within the
/// RANSAC threshold of it (ascending).
#[derive(Clone, Debug, PartialEq)]
pub struct PlaneFit {
    /// The centroid of the inliers of the refined plane (a point on the plane).
    pub point: DVec3,
    /// Unit normal. Its sign is arbitrary: see [`orient_towards`].
    pub normal: DVec3,
    pub inliers: Vec<usize>,
}

/// Triples whose spanned parallelogram is smaller than this fraction of the product of the two
/// edge lengths (the sine of the angle between them) are treated as collinear: their plane
/// normal would be dominated by rounding.
const COLLINEAR_SINE: f64 = 1e-9;

/// Fit a plane to `points` by RANSAC: `iterations` hypotheses from random 3-point samples (collinear
/// or coincident triples are skipped, and still count as an iteration so that the run time is
/// bounded), scored by the number of points with `|distance| <= threshold`. The best hypothesis
/// (the first one on ties) is refined by least squares over its inliers, i.e. the plane through
/// their centroid whose normal is the eigenvector of the smallest eigenvalue of their covariance,
/// and the inliers are recomputed once against the refined plane.
///
/// Returns `None` for fewer than 3 points, a non-finite or negative threshold, or when no sampled
/// triple spans a plane (all points coincident or collinear).
pub fn ransac_plane(
    points: &[DVec3],
    threshold: f64,
    iterations: usize,
    rng: &mut Rng,
) -> Option<PlaneFit> {
    let n = points.len();
    if n < 3 || !(threshold >= 0.0 && threshold.is_finite()) {
        return None;
    }
    let mut best: Option<(usize, DVec3, DVec3)> = None;
    for _ in 0..iterations {
        let Some((i, j, k)) = distinct_triple(n, rng) else { continue };
        let Some(normal) = triple_normal(points[i], points[j], points[k]) else { continue };
        let origin = points[i];
        let count =
            points.iter().filter(|p| ((**p - origin).dot(normal)).abs() <= threshold).count();
        if best.is_none_or(|(c, _, _)| count > c) {
            best = Some((count, origin, normal));
        }
    }
    let (_, origin, normal) = best?;
    let inliers = inliers_of(points, origin, normal, threshold);
    // The least-squares plane needs at least three non-collinear inliers; with fewer (a threshold
    // so small that only the sample itself is within it after rounding) keep the hypothesis.
    let (point, normal) = least_squares_plane(points, &inliers).unwrap_or((origin, normal));
    let inliers = inliers_of(points, point, normal, threshold);
    Some(PlaneFit { point, normal, inliers })
}

/// Flip `normal` (and return it normalised) so that most `viewpoints` lie on its front side,
/// `(c - point) . n > 0`. RANSAC's sign is arbitrary, while the renderer's front side is where the
/// annotated cameras are. Ties, and viewpoints exactly on the plane, keep the given sign.
pub fn orient_towards(normal: DVec3, point: DVec3, viewpoints: &[DVec3]) -> DVec3 {
    let n = normal.normalize_or_zero();
    let (mut front, mut back) = (0usize, 0usize);
    for c in viewpoints {
        let s = (*c - point).dot(n);
        if s > 0.0 {
            front += 1;
        } else if s < 0.0 {
            back += 1;
        }
    }
    if back > front { -n } else { n }
}

/// Three distinct indices below `n` (n >= 3), or `None` if the draw collided too often (which
/// only a broken generator would cause; it keeps the loop bounded regardless).
fn distinct_triple(n: usize, rng: &mut Rng) -> Option<(usize, usize, usize)> {
    for _ in 0..64 {
        let (i, j, k) = (rng.below(n), rng.below(n), rng.below(n));
        if i != j && j != k && i != k {
            return Some((i, j, k));
        }
    }
    None
}

/// The unit normal of the plane through three points, `None` if they are (nearly) collinear.
fn triple_normal(a: DVec3, b: DVec3, c: DVec3) -> Option<DVec3> {
    let (ab, ac) = (b - a, c - a);
    let cross = ab.cross(ac);
    let len = cross.length();
    let scale = ab.length() * ac.length();
    // Written so that NaN (from non-finite input) also counts as degenerate.
    let spans = len.is_finite() && len > COLLINEAR_SINE * scale;
    if !spans {
        return None;
    }
    Some(cross / len)
}

fn inliers_of(points: &[DVec3], origin: DVec3, normal: DVec3, threshold: f64) -> Vec<usize> {
    (0..points.len()).filter(|&i| (points[i] - origin).dot(normal).abs() <= threshold).collect()
}

/// The total-least-squares plane of `points[indices]`: through the centroid, with the normal
/// along the direction of least variance. `None` for fewer than 3 points or a degenerate spread
/// (the two largest eigenvalues must be clearly non-zero, otherwise the points are collinear and
/// the smallest eigenvector is not determined).
pub(crate) fn least_squares_plane(points: &[DVec3], indices: &[usize]) -> Option<(DVec3, DVec3)> {
    if indices.len() < 3 {
        return None;
    }
    let inv = 1.0 / indices.len() as f64;
    let centroid = indices.iter().map(|&i| points[i]).sum::<DVec3>() * inv;
    // Accumulate the covariance about the centroid (not E[xx^T] - mm^T) so that a plane far from
    // the origin does not lose its small eigenvalue to cancellation.
    let mut cov = [[0.0f64; 3]; 3];
    for &i in indices {
        let d = (points[i] - centroid).to_array();
        for r in 0..3 {
            for c in 0..3 {
                cov[r][c] += d[r] * d[c] * inv;
            }
        }
    }
    let (values, vectors) = symmetric_eigen(cov);
    // Eigenvalues come sorted ascending; a plane needs two directions of real spread.
    let planar = values[2].is_finite() && values[1] > 1e-12 * values[2];
    if !planar {
        return None;
    }
    let normal = vectors.col(0).normalize_or_zero();
    if normal == DVec3::ZERO {
        return None;
    }
    Some((centroid, normal))
}

/// Eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi rotations. Returns the
/// eigenvalues in ascending order and the matrix whose columns are the matching unit
/// eigenvectors. Jacobi is slower than a closed form but accurate for nearly equal eigenvalues,
/// which is exactly the planar case (two large, one tiny) we care about.
pub fn symmetric_eigen(m: [[f64; 3]; 3]) -> ([f64; 3], DMat3) {
    let mut a = m;
    // v accumulates the rotations; its columns end up as the eigenvectors.
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _sweep in 0..50 {
        let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        let diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        // Converged once the off-diagonal mass is at rounding level relative to the diagonal
        // (or exactly zero, which also covers the zero matrix).
        if off <= 1e-30 * diag || off == 0.0 {
            break;
        }
        for (p, q) in [(0usize, 1usize), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            // Rotation angle that zeroes a[p][q] (Numerical Recipes' stable form).
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            // A <- J^T A J with J the rotation in the (p, q) plane.
            for k in 0..3 {
                let (akp, akq) = (a[k][p], a[k][q]);
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for k in 0..3 {
                let (apk, aqk) = (a[p][k], a[q][k]);
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for k in 0..3 {
                let (vkp, vkq) = (v[k][p], v[k][q]);
                v[k][p] = c * vkp - s * vkq;
                v[k][q] = s * vkp + c * vkq;
            }
        }
    }
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| a[i][i].total_cmp(&a[j][j]));
    let values = order.map(|i| a[i][i]);
    let cols = order.map(|i| DVec3::new(v[0][i], v[1][i], v[2][i]));
    (values, DMat3::from_cols(cols[0], cols[1], cols[2]))
}
