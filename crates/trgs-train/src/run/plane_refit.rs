//! The refit of the planes kept by a trial (`--planes auto`, [`super::plane_trial`]): each is
//! moved onto the glass its trained layers show, as painted masks move their planes at
//! initialisation (`planes::init`).
use super::glass_pixels::{GlassEvidence, NOT_GLASS, glass_pixels};
use super::plane_trial::rows_only_shown_by_each;
use super::refit_offset::{OffsetChoice, offset_along_normal};
use super::refit_wall::{Proposed, WallFrame, into_opening};
use super::{RunEvent, TrainingRun};
use crate::planes::init::{PlaneInitSettings, fit_to_outline, outline_gaussians};
use anyhow::Result;
use glam::DVec3;
use trgs_core::Image;
use trgs_core::fit::{SilhouetteFit, SilhouetteSettings, refine_to_masks};
use trgs_core::plane_carry::PlaneCarry;
use trgs_core::rng::Rng;
use trgs_core::scene::{Camera, Gaussians, ReflectionPlane};

impl TrainingRun {
    /// Move each kept plane's rectangle onto its glass: where the training views hit it and the
    /// trained layers say glass ([`glass_pixels`], read by the plane's [`GlassEvidence`]), taken
    /// as each view's glass mask for the masks' own refinement (`fit::refine_to_masks`). The
    /// first rectangle is the see-through region of the proposal, which the frame and the sight
    /// lines past its edges widen. Where the glass so found pins no rectangle within the
    /// refinement's limits, the learned mask alone is tried. `proposals` says what each kept
    /// plane's proposal found: a point of its structure's plane, which bounds the refit's offset
    /// ([`offset_along_normal`]), and the wall it was found turned in, if any
    /// ([`super::refit_wall`]).
    pub(super) fn fit_kept_to_their_glass(&mut self, proposals: &[Proposed]) -> Result<()> {
        let trained = self.trainer.planes().to_vec();
        let mut planes = trained.clone();
        let masks = self.glass_labels(&planes)?;
        let g = self.trainer.gaussians()?;
        let extent = self.data.extent;
        let cameras: Vec<&Camera> = self.data.train.iter().map(|v| &v.camera).collect();
        let proposed = |k: usize| proposals.get(k).copied().unwrap_or_default();
        // A plane found turned in a wall's opening whose glass the wall frames: into the
        // opening, over the wall's sight lines through it. Its glass is not refitted there: the
        // pixels it was trained over show the structure it stood on close behind the wall
        // along the line where the two planes meet, which a rectangle in the opening would
        // leave out.
        let mut moved_into_opening: Vec<Option<WallFrame>> = vec![None; planes.len()];
        for (k, list) in masks.iter().enumerate() {
            let Some(opening) = proposed(k).opening else { continue };
            let glass = Glass { list, evidence: GlassEvidence::of(list), proposal: None };
            let owned = glass.views(&cameras);
            let views = borrowed(&owned);
            let init = PlaneInitSettings::default();
            let outline = outline_gaussians(&g, &views, 1, &init);
            let frame =
                WallFrame::count(&opening, &planes[k], &outline, init.ransac_threshold * extent);
            if frame.frames() {
                planes[k] = into_opening(&planes[k], &opening);
                moved_into_opening[k] = Some(frame);
            }
        }
        for (k, list) in masks.iter().enumerate() {
            if let Some(frame) = moved_into_opening[k] {
                let (p, t) = (&planes[k], &trained[k]);
                self.events.push_back(RunEvent::Note(format!(
                    "kept plane {k}: turned {:.2} deg into the opening of the wall it was found \
                     turned in, whose plane holds {} of the Gaussians around its glass and its \
                     own {}: {:.2} x {:.2} -> {:.2} x {:.2}, centre moved {:.3}",
                    p.unit_normal().angle_between(t.unit_normal()).to_degrees(),
                    frame.on_wall,
                    frame.on_pane,
                    t.width,
                    t.height,
                    p.width,
                    p.height,
                    p.centre.distance(t.centre)
                )));
                continue;
            }
            let before = planes[k];
            let evidence = GlassEvidence::of(list);
            let proposal = proposed(k).point;
            let refit = |e: GlassEvidence| {
                let on = Glass { list, evidence: e, proposal };
                refit_to_glass(&before, &cameras, &on, &g, extent, &self.rng)
            };
            // Glass seen through whose seen-through pixels pin no rectangle: its mask alone.
            let fallback = (evidence != GlassEvidence::Mask).then_some(GlassEvidence::Mask);
            let fitted = refit(evidence)
                .map(|r| (r, evidence.describe()))
                .or_else(|| fallback.and_then(refit).map(|r| (r, "its mask alone")));
            let text = match fitted {
                Some((refit, by)) => {
                    planes[k] = refit.fit.plane;
                    refit.describe(&trained[k], by)
                }
                None => format!(
                    "kept as proposed (its glass in {} views pins no rectangle)",
                    list.len()
                ),
            };
            self.events.push_back(RunEvent::Note(format!("kept plane {k}: {text}")));
        }
        // What only a refitted plane's mirrored pass shows moves with it, so that the
        // reflection its trial trained stays where the photos put it: the reflection seeds were
        // placed, and trained, about the plane as it stood.
        let carries: Vec<Option<PlaneCarry>> = (0..planes.len())
            .map(|k| {
                let carry = PlaneCarry::between(&trained[k], &planes[k], 0);
                (moved_into_opening[k].is_none() && carry.moves()).then_some(carry)
            })
            .collect();
        let mut carried = vec![Vec::new(); planes.len()];
        if carries.iter().any(Option::is_some) {
            carried = rows_only_shown_by_each(&g, &trained, &cameras);
        }
        for (k, (rows, carry)) in carried.iter_mut().zip(&carries).enumerate() {
            let Some(carry) = carry else {
                rows.clear();
                continue;
            };
            if !rows.is_empty() {
                let centre = trained[k].centre;
                self.events.push_back(RunEvent::Note(format!(
                    "kept plane {k}: the {} Gaussians only it shows moved with it, {:.3} at its \
                     centre (their mirror images stay)",
                    rows.len(),
                    carry.point(centre).distance(centre)
                )));
            }
        }
        self.trainer.move_planes(&planes, &carried)?;
        let moved: Vec<usize> =
            (0..planes.len()).filter(|&k| moved_into_opening[k].is_some()).collect();
        if moved.is_empty() { Ok(()) } else { self.start_over_in_openings(&trained, &moved) }
    }

    /// Each of `planes`' [`glass_pixels`] labels in an even sample of the training views
    /// ([`REFIT_VIEWS`]): those that show any of its glass, with their indices.
    fn glass_labels(&mut self, planes: &[ReflectionPlane]) -> Result<Vec<LabelledViews>> {
        let n = self.data.train.len();
        let stride = n.div_ceil(REFIT_VIEWS).max(1);
        let mut labels: Vec<LabelledViews> = vec![Vec::new(); planes.len()];
        for vi in (0..n).step_by(stride) {
            let view = &self.data.train[vi];
            let images = self.trainer.render_with_planes(planes, &view.camera)?;
            for (k, list) in labels.iter_mut().enumerate() {
                let m = glass_pixels(k, &planes[k], &view.camera, &images);
                if m.data.iter().any(|&v| v != NOT_GLASS) {
                    list.push((vi, m));
                }
            }
        }
        Ok(labels)
    }
}

/// The turns of a kept plane to the frame around its learned glass ([`fit_to_outline`]) that
/// are taken. The frame is narrow, so its plane scatters: on panes whose proposal stood within
/// half a degree of the truth it measured 0.2-0.7 deg off (walk-by once 1.03, turned to 0.88
/// from 0.31; docs/RESULTS.md, "Planes without masks"); below the least turn the proposal's
/// plane, fitted over the wider structure, is kept. A fit turned past the most stands on
/// something else (a wall beside the pane).
const OUTLINE_TURN_DEG: std::ops::RangeInclusive<f64> = 1.0..=10.0;

/// What [`refit_to_glass`] did.
struct GlassRefit {
    fit: SilhouetteFit,
    /// Views whose glass pixels took part.
    views: usize,
    /// How far the plane was turned to the frame around its glass (None: its normal kept).
    turned_deg: Option<f64>,
    /// How far the plane of the frame around its glass stood from it (None: no fit).
    outline_deg: Option<f64>,
    /// The offset along the normal it took ([`offset_along_normal`]).
    offset: OffsetChoice,
}

/// What a kept plane's glass is refitted to: its views' [`glass_pixels`] labels (index into
/// the training cameras), the evidence that reads them, and a point of its proposal's plane.
struct Glass<'a> {
    list: &'a [(usize, Image<u8>)],
    evidence: GlassEvidence,
    proposal: Option<DVec3>,
}

impl Glass<'_> {
    /// Each view's pixels that the evidence takes, less their small pieces
    /// ([`GLASS_PIECE_FRACTION`]), in the views that keep any; index into `cameras`.
    fn views<'c>(&self, cameras: &[&'c Camera]) -> Vec<(&'c Camera, Image<u8>)> {
        self.list
            .iter()
            .map(|(vi, m)| {
                let data = m.data.iter().map(|&v| u8::from(self.evidence.takes(v))).collect();
                (cameras[*vi], Image { data, ..*m }.without_small_pieces(GLASS_PIECE_FRACTION))
            })
            .filter(|(_, m)| m.data.contains(&1))
            .collect()
    }
}

impl GlassRefit {
    /// What the refit did to `trained` (the plane the trial trained), by the glass `by`
    /// ([`GlassEvidence::describe`]), for the kept-plane line of `train`.
    fn describe(&self, trained: &ReflectionPlane, by: &str) -> String {
        let turn = match (self.turned_deg, self.outline_deg) {
            (Some(deg), _) => format!("; turned {deg:.2} deg to the frame around it"),
            (None, Some(deg)) => format!("; the frame around it {deg:.2} deg off, not turned to"),
            (None, None) => String::new(),
        };
        let p = &self.fit.plane;
        format!(
            "moved onto its glass ({by} in {} views{turn}): {:.2} x {:.2} -> {:.2} x {:.2}, centre \
             moved {:.3}; {}",
            self.views,
            trained.width,
            trained.height,
            p.width,
            p.height,
            p.centre.distance(trained.centre),
            self.offset.describe()
        )
    }
}

/// [`Glass::views`] as the silhouette fits take them.
fn borrowed<'a>(views: &'a [(&'a Camera, Image<u8>)]) -> Vec<(&'a Camera, &'a Image<u8>)> {
    views.iter().map(|(c, m)| (*c, m)).collect()
}

/// Pieces of a view's glass smaller than this fraction of its largest piece are left out of the
/// refit: the sight lines past a turned pane's frame through the gap it leaves in its opening
/// see through its plane too, beyond the frame, and a rectangle stretched over the frame to
/// take them in costs less than it gains (covered pixels that are not glass count
/// [`SilhouetteSettings::outside_weight`]). Panes of one facade, apart between mullions, are
/// of a size and stay.
const GLASS_PIECE_FRACTION: f64 = 0.25;

/// `before` moved onto the pixels of `list` (index into `cameras`, [`glass_pixels`] labels) that
/// `evidence` takes ([`Glass::views`]): as the masks' planes are initialised
/// ([`fit_to_outline`], then `fit::refine_to_masks`), the plane of the Gaussians `g` around the
/// glass's outline first ([`outline_plane`]), where it turns `before` within
/// [`OUTLINE_TURN_DEG`]; the proposal's normal comes from whatever structure it found, which for
/// a pane turned in its opening is a fragment of its frame. From `before` itself where the
/// outline's plane pins no rectangle.
///
/// The rectangle moves within its plane, at the offset along the normal that
/// [`offset_along_normal`] takes.
fn refit_to_glass(
    before: &ReflectionPlane,
    cameras: &[&Camera],
    glass: &Glass,
    g: &Gaussians<f32>,
    extent: f64,
    rng: &Rng,
) -> Option<GlassRefit> {
    let owned = glass.views(cameras);
    let views = borrowed(&owned);
    let settings = SilhouetteSettings { hold_offset: true, ..SilhouetteSettings::default() };
    let outlined = outline_plane(before, &views, g, extent, rng)
        .map(|outline| turned_onto(before, &outline))
        .map(|p| (p, p.unit_normal().angle_between(before.unit_normal()).to_degrees()));
    let outline_deg = outlined.map(|(_, deg)| deg);
    let refit_from = |start: &ReflectionPlane| {
        let offset = match glass.evidence {
            GlassEvidence::SeenThrough => offset_along_normal(start, &views, glass.proposal),
            // A mirror's mask spills onto its frame, in front of it like the proposal's
            // structure: the median would not stand between two opposite failures.
            GlassEvidence::Mask => OffsetChoice::trial(),
        };
        let mut at = *start;
        at.centre += start.unit_normal() * offset.taken;
        refine_to_masks(&at, &views, 1, &settings).map(|fit| (fit, offset))
    };
    let turned = outlined
        .filter(|(_, deg)| OUTLINE_TURN_DEG.contains(deg))
        .and_then(|(start, deg)| refit_from(&start).map(|(fit, offset)| (fit, offset, Some(deg))));
    let (fit, offset, turned_deg) =
        turned.or_else(|| refit_from(before).map(|(fit, offset)| (fit, offset, None)))?;
    Some(GlassRefit { fit, views: views.len(), turned_deg, outline_deg, offset })
}

/// The plane of the Gaussians `g` around the outline of the glass of `plane` in `views`
/// ([`fit_to_outline`]): its normal alone is of use, since the minimum-area box of its inliers
/// also takes in whatever else lies in that plane near the glass (the wall along a hinge), and
/// the refinement counts only the pixels near each view's glass, so it cannot shrink a
/// rectangle that reaches far past them. Fitted on a copy of the run's random stream, so that a
/// plane left as proposed trains as it did before the fit was tried.
fn outline_plane(
    plane: &ReflectionPlane,
    views: &[(&Camera, &Image<u8>)],
    g: &Gaussians<f32>,
    extent: f64,
    rng: &Rng,
) -> Option<ReflectionPlane> {
    let init = PlaneInitSettings::default();
    fit_to_outline(g, views, 1, plane.material, extent, &init, &mut rng.clone()).ok()
}

/// `plane`'s rectangle turned parallel to `onto` about its own centre (its offset is chosen
/// after, [`offset_along_normal`]), its axis made orthogonal to `onto`'s normal; its size and
/// material as they are.
fn turned_onto(plane: &ReflectionPlane, onto: &ReflectionPlane) -> ReflectionPlane {
    let n = onto.unit_normal();
    let mut turned = ReflectionPlane { normal: n, ..*plane };
    turned.orthogonalise_axis();
    turned
}

/// A plane's [`glass_pixels`] labels in the views that show its glass, with their indices into
/// the training views.
type LabelledViews = Vec<(usize, Image<u8>)>;

/// Training views (an even sample) whose learned mask refits the kept planes.
const REFIT_VIEWS: usize = 16;

#[cfg(test)]
mod tests {
    use super::super::glass_pixels::{MASKED, SEEN_THROUGH};
    use super::*;
    use glam::DVec3;
    use trgs_core::scene::Population;

    /// A 1 x 0.8 pane in z = 0 inside a frame of opaque Gaussians 0.1 wide, and eight cameras
    /// 2.5 from it on an arc of 70 degrees.
    fn framed_pane() -> (ReflectionPlane, Gaussians<f32>, Vec<Camera>) {
        use trgs_core::scene::{Intrinsics, Material, Pose};
        let truth =
            ReflectionPlane::new(DVec3::ZERO, DVec3::Z, DVec3::X, 1.0, 0.8, Material::Glass);
        let mut rng = Rng::new(5);
        let mut g = Gaussians::empty(0);
        while g.len() < 600 {
            let p = DVec3::new(rng.range(-0.6, 0.6), rng.range(-0.5, 0.5), 0.0);
            if p.x.abs() > 0.5 || p.y.abs() > 0.4 {
                g.push(
                    [p.x as f32, p.y as f32, 0.0],
                    [1.0, 0.0, 0.0, 0.0],
                    [-4.0; 3],
                    2.0,
                    &[[0.5; 3]],
                    Population::Primary,
                );
            }
        }
        let k = Intrinsics::from_fov_x(60f64.to_radians(), 128, 96);
        let cameras = (0..8)
            .map(|i| {
                let a = (-40.0 + 10.0 * f64::from(i)).to_radians();
                let eye = DVec3::new(2.5 * a.sin(), 0.3 * a.cos(), 2.5 * a.cos());
                Camera::new(format!("c{i}"), k, Pose::look_at(eye, DVec3::ZERO, DVec3::Y))
            })
            .collect();
        (truth, g, cameras)
    }

    /// Each camera's [`glass_pixels`] labels, from where each pixel's ray meets the planes
    /// z = const (`label`'s argument gives the point for a z).
    fn labelled_views(
        cameras: &[Camera],
        label: impl Fn(&dyn Fn(f64) -> DVec3) -> u8,
    ) -> Vec<(usize, Image<u8>)> {
        cameras
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let (w, h) = (c.intrinsics.width, c.intrinsics.height);
                let mut m = Image::<u8>::new(w, h, 1);
                for y in 0..h {
                    for x in 0..w {
                        let (o, d) = (c.pose.centre(), c.pixel_ray(x, y));
                        let at = |z: f64| o + d * ((z - o.z) / d.z);
                        m.data[(y * w + x) as usize] = label(&at);
                    }
                }
                (i, m)
            })
            .collect()
    }

    #[test]
    fn the_refit_turns_a_plane_to_the_frame_around_its_glass() {
        use trgs_core::scene::Material;
        let (truth, g, cameras) = framed_pane();
        let rng = Rng::new(5);
        // The proposal: a fragment of the frame, turned 5 deg, too wide and off centre.
        let turn = glam::DQuat::from_rotation_y(5f64.to_radians());
        let before = ReflectionPlane::new(
            DVec3::new(0.05, 0.02, 0.0),
            turn * DVec3::Z,
            turn * DVec3::X,
            1.3,
            1.0,
            Material::Glass,
        );
        let on_pane = |q: DVec3| q.x.abs() < 0.5 && q.y.abs() < 0.4;
        let list = labelled_views(&cameras, |at| if on_pane(at(0.0)) { MASKED } else { NOT_GLASS });
        let refs: Vec<&Camera> = cameras.iter().collect();
        let glass = GlassEvidence::Mask;
        let on = Glass { list: &list, evidence: glass, proposal: None };
        let refit = refit_to_glass(&before, &refs, &on, &g, 1.0, &rng).expect("a fit");
        let p = refit.fit.plane;
        let turned = refit.turned_deg.expect("turned to the frame");
        assert!((turned - 5.0).abs() < 0.5, "turned {turned} deg");
        assert!(p.unit_normal().angle_between(DVec3::Z).to_degrees() < 0.5, "{p:?}");
        assert!(p.centre.distance(truth.centre) < 0.02, "{p:?}");
        assert!((p.width - 1.0).abs() < 0.03 && (p.height - 0.8).abs() < 0.03, "{p:?}");
        // The same frame seen as the proposal turned 30 deg: a wall beside it, not turned to.
        let far = glam::DQuat::from_rotation_y(30f64.to_radians());
        let wall = ReflectionPlane { normal: far * DVec3::Z, axis: far * DVec3::X, ..before };
        let kept = refit_to_glass(&wall, &refs, &on, &g, 1.0, &rng);
        assert!(kept.is_none_or(|r| r.turned_deg.is_none()));
    }

    #[test]
    fn the_wall_frames_glass_seen_over_a_structure_turned_behind_it_not_a_pane_in_its_frame() {
        use trgs_core::scene::Material;
        let (truth, g, cameras) = framed_pane();
        // The proposal: a structure of the reflected scene behind the pane, turned 40 deg,
        // which took the wall's opening (grown by a grid cell); its learned mask over the pane.
        let turn = glam::DQuat::from_rotation_y(40f64.to_radians());
        let (normal, axis) = (turn * DVec3::Z, turn * DVec3::X);
        let before = ReflectionPlane::new(
            DVec3::new(0.3, 0.0, -0.5),
            normal,
            axis,
            1.2,
            0.9,
            Material::Glass,
        );
        let opening = ReflectionPlane { width: 1.1, height: 0.9, ..truth };
        let on_pane = |q: DVec3| q.x.abs() < 0.5 && q.y.abs() < 0.4;
        let list = labelled_views(&cameras, |at| if on_pane(at(0.0)) { MASKED } else { NOT_GLASS });
        let refs: Vec<&Camera> = cameras.iter().collect();
        let glass = Glass { list: &list, evidence: GlassEvidence::Mask, proposal: None };
        let owned = glass.views(&refs);
        let views = borrowed(&owned);
        let outline = outline_gaussians(&g, &views, 1, &PlaneInitSettings::default());
        let frame = WallFrame::count(&opening, &before, &outline, 0.01);
        assert!(frame.frames(), "{frame:?} of {} around it", outline.len());
        // Seen the other way, a pane in its own frame turned 40 deg from a wall: not the wall's.
        let wall = ReflectionPlane { normal, axis, ..opening };
        assert!(!WallFrame::count(&wall, &truth, &outline, 0.01).frames());
        // Refitted where it stands, it stays turned (the frame is 40 deg off): hence the move.
        let rng = Rng::new(5);
        let left = refit_to_glass(&before, &refs, &glass, &g, 1.0, &rng);
        assert!(left.is_none_or(|r| r.turned_deg.is_none()));
    }

    #[test]
    fn the_refit_leaves_out_the_frame_the_mask_spills_onto_and_the_gap_past_it() {
        use trgs_core::scene::Material;
        let (truth, g, cameras) = framed_pane();
        let rng = Rng::new(5);
        // The first rectangle, over the frame on both sides (the refit cannot shrink one that
        // reaches well past the glass: its cost counts only pixels near the glass).
        let before = ReflectionPlane::new(
            DVec3::new(0.04, 0.0, 0.0),
            DVec3::Z,
            DVec3::X,
            1.2,
            0.9,
            Material::Glass,
        );
        // The pane is seen through and mostly masked; the learned mask spills onto the frame's
        // right side, and past it the sight lines through the gap a turned pane leaves in its
        // opening see through the plane too.
        let list = labelled_views(&cameras, |at| {
            let q = at(0.0);
            let rows = q.y.abs() < 0.4;
            match q.x {
                x if rows && x.abs() < 0.5 => MASKED | SEEN_THROUGH,
                x if rows && (0.5..0.6).contains(&x) => MASKED,
                x if rows && (0.6..0.68).contains(&x) => SEEN_THROUGH,
                _ => NOT_GLASS,
            }
        });
        let refs: Vec<&Camera> = cameras.iter().collect();
        let evidence = GlassEvidence::of(&list);
        assert_eq!(evidence, GlassEvidence::SeenThrough);
        let on = Glass { list: &list, evidence, proposal: None };
        let refit = refit_to_glass(&before, &refs, &on, &g, 1.0, &rng).expect("a fit");
        let p = refit.fit.plane;
        assert!(p.centre.distance(truth.centre) < 0.02, "{p:?}");
        assert!((p.width - 1.0).abs() < 0.03 && (p.height - 0.8).abs() < 0.03, "{p:?}");
        // By the mask, the frame's side is glass and the rectangle takes it in.
        let on = Glass { evidence: GlassEvidence::Mask, ..on };
        let masked = refit_to_glass(&before, &refs, &on, &g, 1.0, &rng);
        let p = masked.expect("a fit").fit.plane;
        assert!(p.width > 1.07 && p.centre.x > 0.035, "{p:?}");
    }

    #[test]
    fn the_refit_takes_the_median_of_the_trials_the_outlines_and_the_proposals_offsets() {
        use trgs_core::scene::Material;
        let (truth, g, cameras) = framed_pane();
        let rng = Rng::new(5);
        // The pane sits at the front of an opening as large as it and 0.1 deep: a sight line
        // through the glass near one edge meets the opening's side behind it, close behind the
        // plane, and does not see through it (its depth is not SEEN_THROUGH_DEPTH times the
        // plane's).
        let in_opening = |q: DVec3| q.x.abs() < 0.5 && q.y.abs() < 0.4;
        let list = labelled_views(&cameras, |at| {
            if in_opening(at(0.0)) && in_opening(at(-0.1)) { SEEN_THROUGH } else { NOT_GLASS }
        });
        let refs: Vec<&Camera> = cameras.iter().collect();
        // The rectangle too large and off centre, at the offset `z` the trial left it at.
        let trained = |z: f64| {
            let centre = DVec3::new(0.03, -0.02, z);
            ReflectionPlane::new(centre, DVec3::Z, DVec3::X, 1.15, 0.9, Material::Glass)
        };
        let evidence = GlassEvidence::SeenThrough;
        let refit = |z: f64, proposal: Option<f64>| {
            let proposal = proposal.map(|p| DVec3::Z * p);
            let on = Glass { list: &list, evidence, proposal };
            refit_to_glass(&trained(z), &refs, &on, &g, 1.0, &rng).expect("a fit")
        };
        // Free to move along its normal, the rectangle fits the opening between its two ends,
        // behind the glass.
        let views: Vec<(&Camera, &Image<u8>)> = list.iter().map(|(vi, m)| (refs[*vi], m)).collect();
        let free = refine_to_masks(&trained(0.0), &views, SEEN_THROUGH, &Default::default());
        let behind = free.expect("a fit").plane.centre.z;
        assert!(behind < -0.03, "the outline alone at {behind}");
        let on_glass = |r: &GlassRefit| {
            let p = r.fit.plane;
            assert!(p.unit_normal() == DVec3::Z, "{p:?}");
            assert!(p.centre.distance(truth.centre) < 0.02, "{p:?}");
            assert!((p.width - 1.0).abs() < 0.05 && (p.height - 0.8).abs() < 0.05, "{p:?}");
            p.centre.z
        };
        // The trial on the glass, the frame's face 4 cm in front: the trial's offset holds.
        let r = refit(0.0, Some(0.04));
        assert!(on_glass(&r).abs() < 1e-9, "{:?}", r.offset);
        // The trial drifted 6 cm in front, the proposal on the glass: the proposal's.
        let r = refit(0.06, Some(0.0));
        assert!(on_glass(&r).abs() < 1e-9, "{:?}", r.offset);
        // The trial drifted behind the outline's fit: the outline's.
        let r = refit(-0.1, Some(0.04));
        let z = r.fit.plane.centre.z;
        assert!((z - behind).abs() < 0.01, "{z} against the outline's {behind}: {:?}", r.offset);
        // Without a proposal, or for a mirror, the trial's.
        assert!(refit(0.06, None).fit.plane.centre.z == 0.06);
    }
}
