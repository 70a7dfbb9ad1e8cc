//! A capture split into blocks that overlap, to train apart and merge (VastGaussian's and
//! CityGaussian's partition): the blocks' centres tile the ground plane where the cameras stood
//! (k-means), each block's region is the part of the ground nearer its centre than any other's
//! (a Voronoi cell) widened by a margin and holds the points in it, and each block trains on the
//! views that see its region, found from the points they observe rather than from where the
//! camera stands (a camera on the pavement sees the shop across the street).
use crate::rng::Rng;
use glam::{DVec2, DVec3};

pub mod mask_support;
pub mod merge;

/// The share of a view's points in a second block's cell that makes it a seam view
/// ([`Regions::spans_a_seam`]).
pub const SEAM_SHARE: f64 = 0.10;

/// The ground the blocks tile: the plane across the cameras' mean up direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ground {
    pub up: DVec3,
    /// Two unit axes across `up`, the ground's coordinates.
    pub axes: [DVec3; 2],
}

impl Ground {
    /// The ground of cameras with these up directions (world space); None when they cancel out.
    pub fn from_ups(ups: &[DVec3]) -> Option<Self> {
        let up = ups.iter().copied().sum::<DVec3>().try_normalize()?;
        let helper = if up.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
        let a = (helper - up * helper.dot(up)).normalize();
        Some(Self { up, axes: [a, up.cross(a)] })
    }

    /// Where `x` lies on the ground.
    pub fn project(&self, x: DVec3) -> DVec2 {
        DVec2::new(x.dot(self.axes[0]), x.dot(self.axes[1]))
    }
}

/// The blocks' regions on the ground.
#[derive(Clone, Debug, PartialEq)]
pub struct Regions {
    pub centres: Vec<DVec2>,
}

impl Regions {
    /// Whether ground point `p` lies in block `b`'s region widened by `margin`: on `b`'s side of
    /// every bisector with another centre, or within `margin` past it.
    pub fn contains(&self, b: usize, p: DVec2, margin: f64) -> bool {
        let c = self.centres[b];
        self.centres.iter().enumerate().all(|(j, &o)| {
            let Some(dir) = (o - c).try_normalize() else { return true };
            j == b || (p - 0.5 * (c + o)).dot(dir) <= margin
        })
    }

    /// The block whose centre is nearest `p` (the lower index on a tie).
    pub fn owner(&self, p: DVec2) -> usize {
        (0..self.centres.len())
            .min_by(|&a, &b| {
                p.distance_squared(self.centres[a]).total_cmp(&p.distance_squared(self.centres[b]))
            })
            .unwrap_or(0)
    }

    /// Whether a view that observes the ground points `seen` looks across a seam: at least
    /// [`SEAM_SHARE`] of them lie in a cell other than the one most of them lie in. A seam view
    /// shows what two blocks trained apart, side by side.
    pub fn spans_a_seam(&self, seen: &[DVec2]) -> bool {
        let mut counts = vec![0usize; self.centres.len()];
        for &p in seen {
            counts[self.owner(p)] += 1;
        }
        counts.sort_unstable();
        let second = counts.iter().rev().nth(1).copied().unwrap_or(0);
        !seen.is_empty() && second as f64 >= SEAM_SHARE * seen.len() as f64
    }

    /// The median distance from a centre to its nearest other centre (0 for one block).
    pub fn spacing(&self) -> f64 {
        let mut d: Vec<f64> = self
            .centres
            .iter()
            .enumerate()
            .filter_map(|(i, c)| {
                self.centres
                    .iter()
                    .enumerate()
                    .filter(|&(j, _)| j != i)
                    .map(|(_, o)| c.distance(*o))
                    .min_by(f64::total_cmp)
            })
            .collect();
        d.sort_by(f64::total_cmp);
        d.get(d.len() / 2).copied().unwrap_or(0.0)
    }
}

/// `k` centres of `points` by k-means (k-means++ seeding from `seed`, then Lloyd's iterations
/// until no point changes cluster or 100 rounds); fewer when there are fewer distinct points.
pub fn kmeans(points: &[DVec2], k: usize, seed: u64) -> Vec<DVec2> {
    if points.is_empty() || k == 0 {
        return Vec::new();
    }
    let mut rng = Rng::new(seed);
    let mut centres = vec![points[rng.below(points.len())]];
    let mut nearest: Vec<f64> = points.iter().map(|p| p.distance_squared(centres[0])).collect();
    while centres.len() < k {
        let total: f64 = nearest.iter().sum();
        if !(total > 0.0) {
            break;
        }
        let mut pick = rng.uniform() * total;
        let i = nearest
            .iter()
            .position(|&d| {
                pick -= d;
                pick <= 0.0
            })
            .unwrap_or(points.len() - 1);
        centres.push(points[i]);
        for (n, p) in nearest.iter_mut().zip(points) {
            *n = n.min(p.distance_squared(points[i]));
        }
    }
    let mut assignment = vec![usize::MAX; points.len()];
    for _ in 0..100 {
        let regions = Regions { centres: centres.clone() };
        let mut changed = false;
        for (a, p) in assignment.iter_mut().zip(points) {
            let o = regions.owner(*p);
            changed |= *a != o;
            *a = o;
        }
        if !changed {
            break;
        }
        let mut sums = vec![(DVec2::ZERO, 0usize); centres.len()];
        for (&a, p) in assignment.iter().zip(points) {
            sums[a].0 += *p;
            sums[a].1 += 1;
        }
        for (c, (s, n)) in centres.iter_mut().zip(sums) {
            if n > 0 {
                *c = s / n as f64;
            }
        }
    }
    centres
}

/// What one block holds: indices into the capture's points and views.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct BlockPlan {
    /// Points in the block's widened region.
    pub points: Vec<usize>,
    /// Training views that see its region.
    pub train: Vec<usize>,
    /// Test views whose points lie mostly in its region (each test view is in one block only,
    /// so that no block trains on another's test view... and no test view is scored twice).
    pub test: Vec<usize>,
}

/// How views are given to blocks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Assignment {
    /// The region's widening, in scene units.
    pub margin: f64,
    /// A training view trains a block when at least this share of the points it observes lie in
    /// the block's widened region.
    pub min_share: f64,
    /// A block that the share gives fewer training views takes the views that see most of its
    /// region's points, up to this many (a block with too few views cannot train).
    pub min_views: usize,
}

/// The blocks of a capture: `points` on the ground, `observations[v]` the points view `v` sees,
/// `is_test[v]` whether it is a test view. A training view that no block takes by its share goes
/// to the block holding most of its points, so that every view trains somewhere; a block left
/// with fewer than `min_views` training views takes the views that see most of its points.
pub fn plan_blocks(
    regions: &Regions,
    points: &[DVec2],
    observations: &[Vec<usize>],
    is_test: &[bool],
    a: Assignment,
) -> Vec<BlockPlan> {
    let n = regions.centres.len();
    let mut plans = vec![BlockPlan::default(); n];
    let inside: Vec<Vec<bool>> = (0..n)
        .map(|b| points.iter().map(|&p| regions.contains(b, p, a.margin)).collect())
        .collect();
    for b in 0..n {
        plans[b].points = (0..points.len()).filter(|&i| inside[b][i]).collect();
    }
    for (v, seen) in observations.iter().enumerate() {
        // Points per block: in the widened region (training) and owned (test and fallback).
        let widened: Vec<usize> =
            (0..n).map(|b| seen.iter().filter(|&&i| inside[b][i]).count()).collect();
        let mut owned = vec![0usize; n];
        for &i in seen {
            owned[regions.owner(points[i])] += 1;
        }
        let most = (0..n).max_by_key(|&b| (owned[b], std::cmp::Reverse(b))).unwrap_or(0);
        if is_test.get(v).copied().unwrap_or(false) {
            plans[most].test.push(v);
            continue;
        }
        let mut took = false;
        for b in 0..n {
            if !seen.is_empty() && widened[b] as f64 >= a.min_share * seen.len() as f64 {
                plans[b].train.push(v);
                took = true;
            }
        }
        if !took {
            plans[most].train.push(v);
        }
    }
    for (b, plan) in plans.iter_mut().enumerate() {
        if plan.train.len() >= a.min_views {
            continue;
        }
        let mut candidates: Vec<(usize, usize)> = observations
            .iter()
            .enumerate()
            .filter(|&(v, _)| !is_test.get(v).copied().unwrap_or(false) && !plan.train.contains(&v))
            .map(|(v, seen)| (seen.iter().filter(|&&i| inside[b][i]).count(), v))
            .filter(|&(count, _)| count > 0)
            .collect();
        candidates.sort_by(|x, y| y.0.cmp(&x.0).then(x.1.cmp(&y.1)));
        let wanted = a.min_views - plan.train.len();
        plan.train.extend(candidates.into_iter().take(wanted).map(|(_, v)| v));
        plan.train.sort_unstable();
    }
    plans
}

#[cfg(test)]
mod tests;
