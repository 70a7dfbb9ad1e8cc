//! Reflection planes proposed from the scene, without masks: the planar structures of the points
//! ([`find_structures`]), each scored by the points the cameras see through it ([`see_through`]).
//! A structure most cameras face, through which enough points are seen, becomes a candidate: a
//! glass plane over its see-through region. The trainer then tries each candidate and keeps
//! those that pay; this module only proposes.
//!
//! Candidates are taken greedily, the best-evidenced first, and a point seen through a taken
//! candidate no longer counts for the others: the virtual room a window reflects also lies behind
//! the far wall of the room behind the window, and must not make that wall a candidate too.
use glam::DVec3;

use super::openings::{hand_over, opening_holding};
use super::planarity::planarity;
use super::reflector_parts::{Reflector, Sight};
use super::see_through::{SeeThrough, see_through};
use super::structures::{Structure, StructureSettings, find_structures};
use crate::rng::Rng;
use crate::scene::{Camera, ReflectionPlane};

/// Settings of the proposal; distances are fractions of the scene's depth scale (the median
/// distance from the points to the nearest camera): triangulation and splat noise grow with
/// depth, and a video's camera spread (3DGS's extent) can be a small fraction of it.
#[derive(Clone, Debug, PartialEq)]
pub struct ProposalSettings {
    /// At most this many candidates.
    pub max_candidates: usize,
    /// Inlier distance of a structure.
    pub threshold: f64,
    pub ransac_iterations: usize,
    /// At most this many RANSAC planes are searched.
    pub max_structures: usize,
    /// A structure holds at least this fraction of the points (and at least 30 points).
    pub min_support: f64,
    /// Grid cell of the connected pieces and of the see-through region.
    pub cell: f64,
    /// Structures whose normals differ by less than this (degrees) may be merged.
    pub merge_angle_deg: f64,
    /// A structure parallel to a candidate, this close to its plane and touching it is part of
    /// its reflector (the frame, the wall around the glass), not a candidate of its own.
    pub duplicate_offset: f64,
    /// Of the cameras that see a structure, at least this fraction stand in front of it.
    pub min_cameras_in_front: f64,
    /// At least this many points are seen through a candidate...
    pub min_seen_through: usize,
    /// ...and at least this fraction of its points and those seen through it are seen through.
    pub min_seen_fraction: f64,
    /// At most this many cameras (an even subsample) test the sight lines.
    pub max_cameras: usize,
    /// A candidate's [`PlaneCandidate::planarity`] is at least this, or its
    /// [`PlaneCandidate::wall_planarity`] at least [`Self::min_wall_planarity`]; the trial
    /// drops a slice through a cloud that gets past either (docs/RESULTS.md, "Planes without
    /// masks").
    pub min_planarity: f64,
    /// A candidate's [`PlaneCandidate::wall_planarity`] is at least this, or its `planarity` at
    /// least [`Self::min_planarity`]. A mirror's wall scores a low `planarity`: the model grows
    /// the mirrored room right behind the glass, within a few thresholds of its plane (the
    /// family's mirror and two drawn ones scored 0.30-0.39 at step 200 of 2000). That room lies
    /// over the wall's hole: over the cells the wall holds points in, the three walls scored
    /// 0.50-0.60, slices through the objects of a room at most 0.48.
    pub min_wall_planarity: f64,
}

impl Default for ProposalSettings {
    fn default() -> Self {
        Self {
            max_candidates: 4,
            threshold: 0.01,
            ransac_iterations: 1000,
            max_structures: 12,
            min_support: 0.01,
            cell: 0.04,
            merge_angle_deg: 2.0,
            duplicate_offset: 0.08,
            min_cameras_in_front: 0.75,
            min_seen_through: 30,
            min_seen_fraction: 0.05,
            max_cameras: 48,
            min_planarity: 0.4,
            min_wall_planarity: 0.5,
        }
    }
}

/// A planar structure considered for a plane, with its evidence.
#[derive(Clone, Debug, PartialEq)]
pub struct PlaneCandidate {
    /// The glass plane over the see-through region, its normal toward the cameras (None when no
    /// region was found).
    pub plane: Option<ReflectionPlane>,
    /// Points on the structure.
    pub support: usize,
    /// Points seen through it, not already seen through a candidate taken before it.
    pub seen_through: usize,
    /// `seen_through / (seen_through + support)`.
    pub seen_fraction: f64,
    /// Of the cameras that see the structure, the fraction in front of it.
    pub cameras_in_front: f64,
    /// The structure's size (its inliers' minimum-area box), width x height.
    pub structure_size: (f64, f64),
    /// Of the points within `PLANARITY_SLAB` (`super::planarity`) thresholds of its plane inside
    /// its hull, the fraction within one: near 1 for a surface, low for a slice through a cloud.
    pub planarity: f64,
    /// The same over the cells of its plane that hold its points ([`Structure::blocks`]): the
    /// wall around a hole without what is seen through the hole.
    pub wall_planarity: f64,
    /// The candidate (its index here) in an opening of which this one is turned, and whose sight
    /// lines through that opening it took (`super::openings`).
    pub opening_of: Option<usize>,
    /// That opening as a glass plane in the wall's plane over its sight lines' crossings, as
    /// the wall's own candidate would have it (its normal toward the wall's cameras).
    pub opening: Option<ReflectionPlane>,
    /// `None` for a proposed candidate; otherwise why it was not proposed.
    pub rejected: Option<String>,
}

/// The proposal: the scene's depth scale and the candidates.
#[derive(Clone, Debug, PartialEq)]
pub struct Proposal {
    /// The median distance from a point to the nearest camera (of an even sample of both).
    pub scale: f64,
    /// The proposed candidates first, best evidence first, then the rejected structures with
    /// why. A wall that hands an opening to a structure turned in it is judged again in place,
    /// and so is that structure: after it, each candidate's `rejected`, not its place, says
    /// whether it was proposed.
    pub candidates: Vec<PlaneCandidate>,
}

/// Candidates from `points` (Gaussian centres and sparse points) seen by `cameras`.
pub fn propose_planes(
    points: &[DVec3],
    cameras: &[Camera],
    settings: &ProposalSettings,
    rng: &mut Rng,
) -> Proposal {
    let stride = cameras.len().div_ceil(settings.max_cameras.max(1)).max(1);
    let cameras: Vec<&Camera> = cameras.iter().step_by(stride).collect();
    let scale = depth_scale(points, &cameras);
    let candidates = if scale > 0.0 {
        propose_at_scale(points, &cameras, scale, settings, rng)
    } else {
        Vec::new()
    };
    Proposal { scale, candidates }
}

/// The median distance from a point to its nearest camera centre, over up to 4096 points taken
/// evenly; 0 without points or cameras (or when every distance is not finite).
pub fn depth_scale(points: &[DVec3], cameras: &[&Camera]) -> f64 {
    let centres: Vec<DVec3> = cameras.iter().map(|c| c.pose.centre()).collect();
    let stride = points.len().div_ceil(4096).max(1);
    let mut d: Vec<f64> = points
        .iter()
        .step_by(stride)
        .map(|p| centres.iter().map(|c| c.distance(*p)).fold(f64::INFINITY, f64::min))
        .filter(|d| d.is_finite())
        .collect();
    if d.is_empty() {
        return 0.0;
    }
    let mid = d.len() / 2;
    *d.select_nth_unstable_by(mid, f64::total_cmp).1
}

fn propose_at_scale(
    points: &[DVec3],
    cameras: &[&Camera],
    scale: f64,
    settings: &ProposalSettings,
    rng: &mut Rng,
) -> Vec<PlaneCandidate> {
    let threshold = settings.threshold * scale;
    let cell = settings.cell * scale;
    let structure_settings = StructureSettings {
        threshold,
        ransac_iterations: settings.ransac_iterations,
        ransac_sample: 20_000,
        max_planes: settings.max_structures,
        min_support: ((settings.min_support * points.len() as f64).ceil() as usize).max(30),
        cell,
        merge_angle_deg: settings.merge_angle_deg,
        merge_offset: 2.0 * threshold,
    };
    let structures = find_structures(points, &structure_settings, rng);
    let facing: Vec<(DVec3, f64)> =
        structures.iter().map(|s| facing_side(s, points, cameras)).collect();
    let flatness: Vec<(f64, f64)> =
        structures.iter().map(|s| planarity(s, points, threshold)).collect();

    let judge = |k: usize, seen: &SeeThrough| {
        let (front, in_front) = facing[k];
        let mut c = assess(&structures[k], points, front, in_front, seen, cell, settings);
        (c.planarity, c.wall_planarity) = flatness[k];
        if c.rejected.is_none() {
            c.rejected = not_a_surface(&c, settings);
        }
        c
    };

    let mut unexplained = vec![true; points.len()];
    let mut open: Vec<usize> = (0..structures.len()).collect();
    let (mut proposed, mut parts) = (Vec::new(), Vec::new());
    // The structure and sight lines of each of `proposed` (those taken, then those left).
    let mut considered: Vec<(usize, SeeThrough)> = Vec::new();
    while proposed.len() < settings.max_candidates {
        let candidates: Vec<usize> = (0..points.len()).filter(|&i| unexplained[i]).collect();
        let scored: Vec<(usize, SeeThrough, PlaneCandidate)> = open
            .iter()
            .map(|&k| {
                let seen = see_through(
                    &structures[k],
                    facing[k].0,
                    points,
                    &candidates,
                    cameras,
                    threshold,
                );
                let c = judge(k, &seen);
                (k, seen, c)
            })
            .collect();
        let best = scored
            .iter()
            .filter(|(_, _, c)| c.rejected.is_none())
            .max_by_key(|(k, _, c)| (c.seen_through, std::cmp::Reverse(*k)));
        let Some((k, seen, c)) = best.cloned() else {
            let mut rejected = scored;
            rejected.sort_by_key(|(_, _, c)| std::cmp::Reverse(c.seen_through));
            for (k, seen, c) in rejected {
                proposed.push(c);
                considered.push((k, seen));
            }
            break;
        };
        for &i in &seen.points {
            unexplained[i] = false;
        }
        // The frame and the wall around a pane are planes of their own a few centimetres from
        // the glass, with the same see-through evidence; so are the pieces of a wall that the
        // pane splits apart: parts of this candidate's reflector.
        let reflector = Reflector {
            structures: &structures,
            offset: settings.duplicate_offset * scale,
            cell,
            settings,
        };
        let sight = Sight { points, cameras, threshold };
        let taken =
            reflector.take_parts(k, &c, &seen, &scored, proposed.len(), facing[k].0, &sight);
        parts.extend(taken.rejected);
        let c = PlaneCandidate { plane: taken.plane.or(c.plane), ..c };
        open.retain(|&j| j != k && !taken.structures.contains(&j));
        proposed.push(c);
        considered.push((k, seen));
    }
    hand_over_openings(
        &structures,
        &facing,
        &mut considered,
        &mut proposed,
        &judge,
        points,
        cameras,
        cell,
        threshold,
        settings,
    );
    proposed.extend(parts);
    proposed
}

/// Why `c` is not a surface (a slice through a cloud), or None when either of its planarity
/// shares passes its bar.
fn not_a_surface(c: &PlaneCandidate, settings: &ProposalSettings) -> Option<String> {
    let flat =
        c.planarity >= settings.min_planarity || c.wall_planarity >= settings.min_wall_planarity;
    (!flat).then(|| {
        format!(
            "not a surface: {:.0}% of the points near its plane lie on it over its hull, {:.0}% \
             over its own cells (at least {:.0}% over its hull or {:.0}% over its own cells \
             needed)",
            100.0 * c.planarity,
            100.0 * c.wall_planarity,
            100.0 * settings.min_planarity,
            100.0 * settings.min_wall_planarity
        )
    })
}

/// Hand each opening of a candidate that a structure is turned in over to that structure
/// (`super::openings`). An opening is handed over once, to the best-evidenced structure turned
/// in it (taken or not: the wall took the sight lines it would have shown): one that took an
/// opening neither takes another nor hands it on. `considered` holds the structure index and
/// sight lines of each of `proposed`; `judge` makes a candidate of them; `facing` is each
/// structure's front side (and the fraction of its cameras there).
fn hand_over_openings(
    structures: &[Structure],
    facing: &[(DVec3, f64)],
    considered: &mut [(usize, SeeThrough)],
    proposed: &mut [PlaneCandidate],
    judge: &dyn Fn(usize, &SeeThrough) -> PlaneCandidate,
    points: &[DVec3],
    cameras: &[&Camera],
    cell: f64,
    threshold: f64,
    settings: &ProposalSettings,
) {
    for a in 0..considered.len() {
        for b in 0..considered.len() {
            let room =
                proposed.iter().filter(|c| c.rejected.is_none()).count() < settings.max_candidates;
            if b == a
                || proposed[a].rejected.is_some()
                || proposed[a].opening_of.is_some()
                || proposed[b].opening_of.is_some()
                || (proposed[b].rejected.is_some() && !room)
            {
                continue;
            }
            let (wall, pane) = (&structures[considered[a].0], &structures[considered[b].0]);
            let opening = opening_holding(
                wall,
                &considered[a].1,
                pane,
                points,
                cell,
                settings.merge_angle_deg,
            );
            let Some(opening) = opening else { continue };
            let in_wall = considered[a].1.only(&opening.crossings).region_plane(
                wall,
                facing[considered[a].0].0,
                cell,
            );
            let (mut from, mut to) = (considered[a].1.clone(), considered[b].1.clone());
            let front = facing[considered[b].0].0;
            hand_over(wall, &mut from, &opening, &mut to, pane, front, points, cameras, threshold);
            // What takes an opening is a pane: it is itself a candidate once it has it.
            let pane_candidate = judge(considered[b].0, &to);
            if pane_candidate.rejected.is_some() {
                continue;
            }
            let wall_candidate = judge(considered[a].0, &from);
            (considered[a].1, considered[b].1) = (from, to);
            let (opening_of, opening) = (proposed[a].opening_of, proposed[a].opening);
            proposed[a] = PlaneCandidate { opening_of, opening, ..wall_candidate };
            proposed[b] =
                PlaneCandidate { opening_of: Some(a), opening: in_wall, ..pane_candidate };
        }
    }
}

/// The side of `s` that the cameras seeing it stand on (its normal or the negation), and the
/// fraction of them on that side. A camera sees the structure when it sees any of up to 64 of its
/// points, sampled evenly.
fn facing_side(s: &Structure, points: &[DVec3], cameras: &[&Camera]) -> (DVec3, f64) {
    let stride = s.inliers.len().div_ceil(64).max(1);
    let sample: Vec<DVec3> = s.inliers.iter().step_by(stride).map(|&i| points[i]).collect();
    let (mut front, mut back) = (0usize, 0usize);
    for c in cameras {
        if !sample.iter().any(|&p| c.sees(p)) {
            continue;
        }
        if s.signed_distance(c.pose.centre()) >= 0.0 {
            front += 1;
        } else {
            back += 1;
        }
    }
    let seeing = (front + back).max(1) as f64;
    if back > front { (-s.normal, back as f64 / seeing) } else { (s.normal, front as f64 / seeing) }
}

/// The candidate `s` makes, with `seen` the points seen through it from its `front`.
fn assess(
    s: &Structure,
    points: &[DVec3],
    front: DVec3,
    cameras_in_front: f64,
    seen: &SeeThrough,
    cell: f64,
    settings: &ProposalSettings,
) -> PlaneCandidate {
    let support = s.inliers.len();
    let seen_through = seen.points.len();
    let seen_fraction = seen_through as f64 / (seen_through + support).max(1) as f64;
    let flat: Vec<_> = s.inliers.iter().map(|&i| s.to_plane(points[i])).collect();
    let structure_size =
        super::hull::min_area_box(&flat).map_or((0.0, 0.0), |b| (b.width, b.height));
    let plane = seen.region_plane(s, front, cell);
    let rejected = if cameras_in_front < settings.min_cameras_in_front {
        Some(format!(
            "{:.0}% of the cameras that see it stand in front of it (at least {:.0}% needed)",
            100.0 * cameras_in_front,
            100.0 * settings.min_cameras_in_front
        ))
    } else if seen_through < settings.min_seen_through || seen_fraction < settings.min_seen_fraction
    {
        Some(format!(
            "{seen_through} points seen through it, {:.1}% of its own and those (at least {} and \
             {:.1}% needed)",
            100.0 * seen_fraction,
            settings.min_seen_through,
            100.0 * settings.min_seen_fraction
        ))
    } else if plane.is_none() {
        Some("the sight lines through it outline no region".into())
    } else {
        None
    };
    PlaneCandidate {
        plane,
        support,
        seen_through,
        seen_fraction,
        cameras_in_front,
        structure_size,
        planarity: 0.0,
        wall_planarity: 0.0,
        opening_of: None,
        opening: None,
        rejected,
    }
}

#[cfg(test)]
#[path = "propose_tests.rs"]
pub(super) mod tests;
