//! The Gaussians training starts from, as 3DGS makes them: one per sparse point, coloured by the
//! point (SH DC; higher bands zero), isotropic with the scale of the root mean squared distance to
//! its three nearest neighbours, identity rotation, opacity 0.1. MCMC densification starts from
//! the same points at opacity 0.5 and the same scale ([`InitialShape::MCMC`]). Without points
//! (transforms.json scenes) the points are drawn uniformly in a box around the cameras, with
//! random colours.
use glam::DVec3;
use trgs_core::rng::Rng;
use trgs_core::scene::{Gaussians, Population};
use trgs_core::sh::C0;

/// The opacity and size of the initial Gaussians, which the densification strategy's paper sets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InitialShape {
    pub opacity: f64,
    /// Scale as a multiple of the root mean squared distance to the three nearest points.
    pub scale_factor: f64,
}

impl InitialShape {
    /// 3DGS: `inverse_sigmoid(0.1)` and the neighbour distance.
    pub const CLASSIC: Self = Self { opacity: 0.1, scale_factor: 1.0 };
    /// MCMC densification: 3DGS-MCMC's opacity 0.5 (its `create_from_pcd`), at 3DGS's scale.
    /// Its growth copies Gaussians in proportion to opacity and splits the opacity among the
    /// copies, so from 0.1 a short run's Gaussians stay semi-transparent; 3DGS-MCMC's tenth of the
    /// neighbour distance leaves the first images full of holes that a run of a few thousand
    /// steps does not fill.
    pub const MCMC: Self = Self { opacity: 0.5, scale_factor: 1.0 };
}

/// A point with its colour in [0, 1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeedPoint {
    pub position: DVec3,
    pub color: [f64; 3],
}

/// Uniform random points in the box `[lo, hi]` with random colours (3DGS's random init).
pub fn random_points(count: usize, lo: DVec3, hi: DVec3, rng: &mut Rng) -> Vec<SeedPoint> {
    (0..count)
        .map(|_| SeedPoint {
            position: DVec3::new(
                rng.range(lo.x, hi.x),
                rng.range(lo.y, hi.y),
                rng.range(lo.z, hi.z),
            ),
            color: [rng.uniform(), rng.uniform(), rng.uniform()],
        })
        .collect()
}

/// The points the Gaussians start from: the scene's sparse `points`, or `random_init` random
/// points within `extent` of the cameras' `centre` when it has none or when they cannot seed a
/// scene (all at one spot: every Gaussian would get the smallest scale, no tile would see one,
/// and training would learn nothing); with the line that says which, when it is not the sparse
/// points.
pub fn seed_points(
    points: &[(DVec3, [f64; 3])],
    centre: DVec3,
    extent: f64,
    random_init: usize,
    rng: &mut Rng,
) -> (Vec<SeedPoint>, Option<String>) {
    let r = extent;
    let around = format!("{random_init} random points within {r:.2} of the cameras' centre");
    let random = |rng: &mut Rng| random_points(random_init, centre - r, centre + r, rng);
    if points.is_empty() {
        return (random(rng), Some(format!("no sparse points: {around}")));
    }
    let positions: Vec<DVec3> = points.iter().map(|p| p.0).collect();
    let spread = rms_spread(&positions);
    if !(spread > DEGENERATE_SPREAD * r) {
        let line = format!(
            "the {} sparse points lie at one spot (spread {spread:.1e} in a scene of extent \
             {r:.2}): they cannot seed Gaussians, so training starts from {around}",
            points.len()
        );
        return (random(rng), Some(line));
    }
    let seeds = points.iter().map(|&(position, color)| SeedPoint { position, color });
    (seeds.collect(), None)
}

/// Points of a spread below this fraction of the scene's extent are taken to be one spot.
const DEGENERATE_SPREAD: f64 = 1e-6;

/// Root mean squared distance of `points` to their mean (not finite for non-finite points).
fn rms_spread(points: &[DVec3]) -> f64 {
    let n = points.len().max(1) as f64;
    let mean = points.iter().copied().sum::<DVec3>() / n;
    (points.iter().map(|p| p.distance_squared(mean)).sum::<f64>() / n).sqrt()
}

/// One primary Gaussian per point (see the module text).
pub fn gaussians_from_points(
    points: &[SeedPoint],
    sh_degree: u32,
    shape: InitialShape,
) -> Gaussians<f32> {
    let mut g = Gaussians::<f32>::empty(sh_degree);
    let positions: Vec<DVec3> = points.iter().map(|p| p.position).collect();
    let dist2 = mean_sq_distance_to_neighbours(&positions, 3);
    let coeffs = g.sh_coeffs();
    let logit = (shape.opacity / (1.0 - shape.opacity)).ln() as f32;
    let ln_factor = shape.scale_factor.ln();
    for (p, d2) in points.iter().zip(dist2) {
        let log_scale = (0.5 * d2.max(1e-14).ln() + ln_factor) as f32;
        let mut sh = vec![[0.0f32; 3]; coeffs];
        sh[0] = p.color.map(|c| ((c - 0.5) / C0) as f32);
        g.means.push(p.position.to_array().map(|v| v as f32));
        g.rotations.push([1.0, 0.0, 0.0, 0.0]);
        g.log_scales.push([log_scale; 3]);
        g.opacity_logits.push(logit);
        g.sh.extend(sh);
        g.mask_logits.push(0.0);
        g.log_reflections.push(0.0);
        g.populations.push(Population::Primary);
    }
    g
}

/// For each point, the mean squared distance to its `k` nearest other points (3DGS's
/// `distCUDA2`), from a k-d tree (median splits), which stays fast for points on surfaces and
/// lines, where uniform grids degrade.
pub fn mean_sq_distance_to_neighbours(points: &[DVec3], k: usize) -> Vec<f64> {
    if points.len() <= 1 {
        return vec![1e-4; points.len()];
    }
    let k = k.min(points.len() - 1);
    let tree = KdTree::build(points);
    points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let mut best: Vec<f64> = Vec::with_capacity(k + 1);
            tree.nearest(0, tree.order.len(), *p, i as u32, k, &mut best);
            best.iter().sum::<f64>() / best.len().max(1) as f64
        })
        .collect()
}

/// A k-d tree stored implicitly: `order[lo..hi]` is a node, split at its middle element along
/// `axis[mid]`.
struct KdTree<'a> {
    points: &'a [DVec3],
    order: Vec<u32>,
    axis: Vec<u8>,
}

impl<'a> KdTree<'a> {
    fn build(points: &'a [DVec3]) -> Self {
        let mut t =
            Self { points, order: (0..points.len() as u32).collect(), axis: vec![0; points.len()] };
        t.split(0, points.len());
        t
    }

    fn split(&mut self, lo: usize, hi: usize) {
        if hi - lo <= 1 {
            return;
        }
        let (mut mn, mut mx) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for &i in &self.order[lo..hi] {
            mn = mn.min(self.points[i as usize]);
            mx = mx.max(self.points[i as usize]);
        }
        let ext = mx - mn;
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        let mid = (lo + hi) / 2;
        let pts = self.points;
        self.order[lo..hi].select_nth_unstable_by(mid - lo, |&a, &b| {
            pts[a as usize][axis].total_cmp(&pts[b as usize][axis])
        });
        self.axis[mid] = axis as u8;
        self.split(lo, mid);
        self.split(mid + 1, hi);
    }

    /// Insert into `best` (ascending, at most k) the squared distances from `p` to the points of
    /// node `[lo, hi)` other than `skip`.
    fn nearest(&self, lo: usize, hi: usize, p: DVec3, skip: u32, k: usize, best: &mut Vec<f64>) {
        if lo >= hi {
            return;
        }
        let mid = (lo + hi) / 2;
        let j = self.order[mid];
        if j != skip {
            let d2 = p.distance_squared(self.points[j as usize]);
            if best.len() < k || d2 < best[k - 1] {
                let at = best.partition_point(|&b| b <= d2);
                best.insert(at, d2);
                best.truncate(k);
            }
        }
        let axis = self.axis[mid] as usize;
        let diff = p[axis] - self.points[j as usize][axis];
        let (near, far) =
            if diff < 0.0 { ((lo, mid), (mid + 1, hi)) } else { ((mid + 1, hi), (lo, mid)) };
        self.nearest(near.0, near.1, p, skip, k, best);
        if best.len() < k || diff * diff < best[k - 1] {
            self.nearest(far.0, far.1, p, skip, k, best);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kd_tree_neighbours_match_brute_force() {
        let mut rng = Rng::new(5);
        // A cluster, a far outlier and points on a plane.
        let mut pts: Vec<DVec3> =
            (0..300).map(|_| DVec3::new(rng.normal(), rng.normal(), rng.normal())).collect();
        pts.push(DVec3::new(40.0, 0.0, 0.0));
        pts.extend((0..200).map(|_| DVec3::new(rng.range(-5.0, 5.0), 3.0, rng.range(-5.0, 5.0))));
        let got = mean_sq_distance_to_neighbours(&pts, 3);
        for (i, p) in pts.iter().enumerate() {
            let mut d: Vec<f64> = pts
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|(_, q)| p.distance_squared(*q))
                .collect();
            d.sort_by(f64::total_cmp);
            let want = d[..3].iter().sum::<f64>() / 3.0;
            assert!(
                (got[i] - want).abs() <= 1e-12 * want.max(1.0),
                "point {i}: {} vs {want}",
                got[i]
            );
        }
    }

    #[test]
    fn points_at_one_spot_give_way_to_random_points_with_a_word() {
        let mut rng = Rng::new(7);
        let spot = vec![(DVec3::new(0.5, -1.0, 2.0), [0.2, 0.4, 0.6]); 500];
        let (seeds, said) = seed_points(&spot, DVec3::ZERO, 3.0, 1000, &mut rng);
        let said = said.expect("a line saying what was done");
        assert!(said.contains("500 sparse points lie at one spot"), "{said}");
        assert!(said.contains("1000 random points"), "{said}");
        assert_eq!(seeds.len(), 1000);
        let spread = rms_spread(&seeds.iter().map(|s| s.position).collect::<Vec<_>>());
        assert!(spread > 1.0, "random points fill the cameras' box: spread {spread}");
        // Points with a spread, however small against the scene, are used as they are.
        let cloud: Vec<_> =
            (0..50).map(|i| (DVec3::new(f64::from(i) * 1e-3, 0.0, 2.0), [0.5; 3])).collect();
        let (seeds, said) = seed_points(&cloud, DVec3::ZERO, 3.0, 1000, &mut rng);
        assert_eq!((seeds.len(), said), (50, None));
        let (seeds, said) = seed_points(&[], DVec3::ZERO, 3.0, 10, &mut rng);
        assert!(seeds.len() == 10 && said.is_some_and(|s| s.starts_with("no sparse points")));
    }

    #[test]
    fn gaussians_take_colour_and_spacing() {
        let pts: Vec<SeedPoint> = (0..4)
            .map(|i| SeedPoint {
                position: DVec3::new(f64::from(i), 0.0, 0.0),
                color: [1.0, 0.5, 0.0],
            })
            .collect();
        let g = gaussians_from_points(&pts, 1, InitialShape::CLASSIC);
        assert_eq!(g.len(), 4);
        assert_eq!(g.sh.len(), 16);
        // DC back to colour: 0.5 + C0 * dc.
        let rgb = g.sh[0].map(|v| 0.5 + C0 * f64::from(v));
        assert!((rgb[0] - 1.0).abs() < 1e-6 && (rgb[1] - 0.5).abs() < 1e-6 && rgb[2].abs() < 1e-6);
        // Point 0's neighbours at 1, 2, 3: mean squared distance 14/3.
        assert!((f64::from(g.log_scales[0][0]) - 0.5 * (14.0f64 / 3.0).ln()).abs() < 1e-6);
        assert_eq!(g.opacity_logits[0], (0.1f64 / 0.9).ln() as f32);
        // MCMC's shape: opacity 0.5 (logit 0), its scale factor.
        let m = gaussians_from_points(&pts, 1, InitialShape::MCMC);
        assert_eq!(m.opacity_logits[0], 0.0);
        let ln_factor = f64::from(m.log_scales[0][0] - g.log_scales[0][0]);
        let want = InitialShape::MCMC.scale_factor.ln();
        assert!((ln_factor - want).abs() < 1e-6, "{ln_factor} vs {want}");
    }
}
