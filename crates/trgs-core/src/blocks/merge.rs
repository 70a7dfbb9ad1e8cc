//! Trained blocks into one model: each block keeps the primary Gaussians on its own part of
//! the ground (its Voronoi cell, without the margin it trained with), and planes that several
//! blocks found for one pane become one plane: by the capture's glass masks where it has them
//! (the label each plane covers best; the plane that covers it best stands for the pane, with
//! its glass Gaussians, moved onto all the masks of its label), else by geometry.
use super::mask_support::label_support;
use super::{Ground, Regions};
use crate::fit::{SilhouetteSettings, refine_to_masks};
use crate::image::Image;
use crate::scene::{Camera, Gaussians, Population, ReflectionPlane, sh_coeff_count};
use glam::DVec3;
use std::collections::BTreeMap;

/// How `merge_blocks` tells that planes of several blocks are one pane.
#[derive(Clone, Copy, Debug)]
pub enum PaneEvidence<'a> {
    /// By geometry: [`same_pane`].
    Geometry(SamePane),
    /// By the capture's glass masks (camera, label image at the camera's size): planes that
    /// cover one label best are that pane, and the one covering it best (the block that saw it
    /// whole) is kept with its glass Gaussians; a plane whose best intersection over union is
    /// below `min_iou` covers no pane and is left out.
    Masks { masks: &'a [(&'a Camera, &'a Image<u8>)], min_iou: f64 },
}

/// When two blocks' planes are one pane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SamePane {
    /// Largest angle between their normals, degrees.
    pub max_angle_deg: f64,
    /// Largest distance of one's centre from the other's plane, scene units.
    pub max_offset: f64,
    /// Largest gap between their rectangles within the plane, scene units (0: they must touch).
    pub max_gap: f64,
}

/// One trained block: its Gaussians and planes.
#[derive(Clone, Debug)]
pub struct TrainedBlock {
    pub gaussians: Gaussians<f32>,
    pub planes: Vec<ReflectionPlane>,
}

/// What a merge did, for its report.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MergeReport {
    /// Gaussians kept from each block.
    pub kept: Vec<usize>,
    /// For each merged plane, the (block, plane) pairs it came from, the one it stands on first.
    pub planes_from: Vec<Vec<(usize, usize)>>,
    /// For each merged plane with masks, the label it covers and the intersection over union of
    /// the plane kept.
    pub labels: Vec<(u8, f64)>,
    /// Planes left out, (block, plane, why).
    pub dropped: Vec<(usize, usize, String)>,
}

/// The blocks merged: block `b` (`blocks[b]`, trained on region `b` of `regions`) gives the
/// Gaussians whose centre lies in its cell; the planes are grouped by `evidence`. By geometry
/// (a plane joins a group when it is the same pane as any member) each group becomes one plane
/// ([`merge_planes`]); by masks, each pane keeps its best plane and that plane's glass
/// Gaussians, whichever cells they lie in.
pub fn merge_blocks(
    blocks: &[TrainedBlock],
    ground: &Ground,
    regions: &Regions,
    evidence: PaneEvidence<'_>,
) -> (Gaussians<f32>, Vec<ReflectionPlane>, MergeReport) {
    let degree = blocks.iter().map(|b| b.gaussians.sh_degree).max().unwrap_or(0);
    let mut out = Gaussians::empty(degree);
    let mut report = MergeReport::default();
    let all: Vec<(usize, usize, &ReflectionPlane)> = blocks
        .iter()
        .enumerate()
        .flat_map(|(b, block)| block.planes.iter().enumerate().map(move |(k, p)| (b, k, p)))
        .collect();
    let by_masks = matches!(evidence, PaneEvidence::Masks { .. });
    for (b, block) in blocks.iter().enumerate() {
        let g = &block.gaussians;
        let own = g.subset(|i| {
            // With masks the glass Gaussians go with their plane (below).
            if by_masks && g.populations[i] == Population::Glass {
                return false;
            }
            regions.owner(ground.project(DVec3::from_array(g.means[i].map(f64::from)))) == b
        });
        report.kept.push(own.len());
        out.append(&own);
    }
    let same = match evidence {
        PaneEvidence::Geometry(same) => same,
        PaneEvidence::Masks { masks, min_iou } => {
            let planes = merge_by_masks(blocks, &all, masks, min_iou, &mut out, &mut report);
            debug_assert_eq!(out.sh.len(), out.len() * sh_coeff_count(degree));
            return (out, planes, report);
        }
    };
    debug_assert_eq!(out.sh.len(), out.len() * sh_coeff_count(degree));
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (i, (_, _, p)) in all.iter().enumerate() {
        let joined: Vec<usize> = (0..groups.len())
            .filter(|&gi| groups[gi].iter().any(|&j| same_pane(p, all[j].2, same)))
            .collect();
        match joined.split_first() {
            None => groups.push(vec![i]),
            Some((&first, rest)) => {
                // A plane that bridges groups joins them.
                let mut merged = vec![i];
                for &gi in rest.iter().rev() {
                    merged.extend(groups.remove(gi));
                }
                groups[first].extend(merged);
            }
        }
    }
    let mut planes = Vec::new();
    for group in &groups {
        let members: Vec<&ReflectionPlane> = group.iter().map(|&i| all[i].2).collect();
        planes.push(merge_planes(&members));
        report.planes_from.push(group.iter().map(|&i| (all[i].0, all[i].1)).collect());
    }
    (out, planes, report)
}

/// The planes by the masks (see [`PaneEvidence::Masks`]); appends each kept plane's glass
/// Gaussians to `out`.
fn merge_by_masks(
    blocks: &[TrainedBlock],
    all: &[(usize, usize, &ReflectionPlane)],
    masks: &[(&Camera, &Image<u8>)],
    min_iou: f64,
    out: &mut Gaussians<f32>,
    report: &mut MergeReport,
) -> Vec<ReflectionPlane> {
    let mut panes: BTreeMap<u8, Vec<(usize, f64)>> = BTreeMap::new();
    for (i, &(b, k, p)) in all.iter().enumerate() {
        match label_support(p, masks) {
            Some(s) if s.iou >= min_iou => panes.entry(s.label).or_default().push((i, s.iou)),
            Some(s) => report.dropped.push((
                b,
                k,
                format!("covers label {} of the masks by {:.2} only (IoU)", s.label, s.iou),
            )),
            None => report.dropped.push((b, k, "covers no glass of the masks".into())),
        }
    }
    let mut planes = Vec::new();
    for (label, mut members) in panes {
        members.sort_by(|a, b| b.1.total_cmp(&a.1));
        let (best, iou) = members[0];
        let (b, k, p) = all[best];
        // R0 from every block that found the pane, by how well each covers it.
        let weight: f64 = members.iter().map(|m| m.1).sum();
        let r0 = members.iter().map(|&(i, w)| w * all[i].2.r0()).sum::<f64>() / weight;
        let mut plane = *p;
        // The block saw the pane through its own masked views; the capture's, all of them,
        // place it better (its offset along the normal, its edges).
        if let Some(fit) = refine_to_masks(&plane, masks, label, &SilhouetteSettings::default())
            && fit.cost_after < fit.cost_before
        {
            plane = fit.plane;
        }
        plane.set_r0(r0);
        planes.push(plane);
        out.append(&glass_of(&blocks[b], k));
        report.labels.push((label, iou));
        report.planes_from.push(members.iter().map(|&(i, _)| (all[i].0, all[i].1)).collect());
    }
    planes
}

/// The glass Gaussians of `block` that belong to its plane `k`: those nearer its rectangle than
/// any other of the block's planes (they were sampled on it, or split from such).
fn glass_of(block: &TrainedBlock, k: usize) -> Gaussians<f32> {
    let g = &block.gaussians;
    g.subset(|i| {
        if g.populations[i] != Population::Glass {
            return false;
        }
        let x = DVec3::from_array(g.means[i].map(f64::from));
        let nearest = block
            .planes
            .iter()
            .map(|p| distance_to_rectangle(p, x))
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(j, _)| j);
        nearest == Some(k)
    })
}

/// The distance of `x` from `p`'s rectangle.
fn distance_to_rectangle(p: &ReflectionPlane, x: DVec3) -> f64 {
    let r = x - p.centre;
    let u = (r.dot(p.axis).abs() - 0.5 * p.width).max(0.0);
    let v = (r.dot(p.bitangent()).abs() - 0.5 * p.height).max(0.0);
    let n = r.dot(p.unit_normal());
    (u * u + v * v + n * n).sqrt()
}

/// Whether `a` and `b` are one pane: same material, normals within the angle, each centre near
/// the other's plane, and their rectangles within the gap of each other in `a`'s plane.
pub fn same_pane(a: &ReflectionPlane, b: &ReflectionPlane, same: SamePane) -> bool {
    if a.material != b.material {
        return false;
    }
    let cos = a.unit_normal().dot(b.unit_normal()).clamp(-1.0, 1.0);
    if cos.acos().to_degrees() > same.max_angle_deg {
        return false;
    }
    if a.signed_distance(b.centre).abs() > same.max_offset
        || b.signed_distance(a.centre).abs() > same.max_offset
    {
        return false;
    }
    // The gap between the two rectangles' boxes in a's frame (b's corners projected).
    let (t, h) = (a.axis, a.bitangent());
    let box_of = |p: &ReflectionPlane| {
        let uv: Vec<(f64, f64)> =
            p.corners().iter().map(|c| ((*c - a.centre).dot(t), (*c - a.centre).dot(h))).collect();
        let lo =
            uv.iter().fold((f64::INFINITY, f64::INFINITY), |m, q| (m.0.min(q.0), m.1.min(q.1)));
        let hi = uv
            .iter()
            .fold((f64::NEG_INFINITY, f64::NEG_INFINITY), |m, q| (m.0.max(q.0), m.1.max(q.1)));
        (lo, hi)
    };
    let ((alo, ahi), (blo, bhi)) = (box_of(a), box_of(b));
    let gap_u = (blo.0 - ahi.0).max(alo.0 - bhi.0).max(0.0);
    let gap_v = (blo.1 - ahi.1).max(alo.1 - bhi.1).max(0.0);
    gap_u.max(gap_v) <= same.max_gap
}

/// One plane from several found for one pane: its normal and R0 the area-weighted means, its
/// width axis the largest member's, its rectangle the box of every member's corners in that
/// frame, centred on the weighted mean offset.
pub fn merge_planes(members: &[&ReflectionPlane]) -> ReflectionPlane {
    let largest = members
        .iter()
        .max_by(|a, b| (a.width * a.height).total_cmp(&(b.width * b.height)))
        .map_or(*members[0], |p| **p);
    if members.len() == 1 {
        return largest;
    }
    let reference = largest.unit_normal();
    let (mut normal, mut offset, mut r0, mut area) = (DVec3::ZERO, 0.0, 0.0, 0.0);
    for p in members {
        let w = p.width * p.height;
        // Normals of one pane point the same way; a flipped one would cancel the others.
        let n =
            if p.unit_normal().dot(reference) < 0.0 { -p.unit_normal() } else { p.unit_normal() };
        normal += w * n;
        r0 += w * p.r0();
        area += w;
        offset += w * p.centre.dot(n);
    }
    let n = normal.normalize();
    let offset = offset / area;
    let r0 = r0 / area;
    let mut plane = largest;
    plane.normal = n;
    plane.orthogonalise_axis();
    let (t, h) = (plane.axis, n.cross(plane.axis));
    let anchor = largest.centre - n * (largest.centre.dot(n) - offset);
    let (mut lo, mut hi) = ((f64::INFINITY, f64::INFINITY), (f64::NEG_INFINITY, f64::NEG_INFINITY));
    for p in members {
        for c in p.corners() {
            let (u, v) = ((c - anchor).dot(t), (c - anchor).dot(h));
            lo = (lo.0.min(u), lo.1.min(v));
            hi = (hi.0.max(u), hi.1.max(v));
        }
    }
    plane.centre = anchor + t * (0.5 * (lo.0 + hi.0)) + h * (0.5 * (lo.1 + hi.1));
    plane.width = hi.0 - lo.0;
    plane.height = hi.1 - lo.1;
    plane.set_r0(r0);
    plane
}
