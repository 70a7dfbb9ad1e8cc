//! Planes without masks (`--planes auto`). At the end of stage 1 the scene's planar structures
//! through which the cameras see points are proposed as candidate planes
//! (`trgs_core::fit::propose_planes`); while none is found, the proposal is tried again on the
//! growing model ([`next_proposal_try`]) and stage 1 goes on. Candidates are added as the masks'
//! planes are: glass Gaussians over each one's see-through region, reflection seeds, no offset
//! limit. A fifth of the training views is held out of the steps while they are on trial, and
//! the opacity perturbation waits ([`hold_perturbation_for`]). The trial runs through stage 2
//! (where the Gaussians get no gradient from the mirrored passes, so a plane cannot show yet
//! what it explains) and a tenth of the run into stage 3; then each candidate is switched off in
//! turn on the held-out views and kept only where that raises their L1 by at least
//! [`MIN_L1_GAIN`] and its reflection strength `R` over the pixels it is hit at is at least
//! [`MIN_STRENGTH`]. A dropped candidate's plane (so its mirrored pass) and its glass Gaussians
//! are removed.
use super::candidates::{CandidateRecord, PlaneTrial, next_proposal_try};
use super::{RunEvent, TrainingRun};
use crate::data::View;
use crate::planes::init::{PlaneInitSettings, append_glass, fit_to_outline};
use crate::planes::reflection_seed::UNSEEN_MARGIN;
use crate::settings::TrainSettings;
use anyhow::Result;
use glam::DVec3;
use trgs_core::Image;
use trgs_core::fit::{
    ProposalSettings, SilhouetteFit, SilhouetteSettings, propose_planes, refine_to_masks,
};
use trgs_core::plane_math::{ray_rectangle_hit, reflect_point};
use trgs_core::rng::Rng;
use trgs_core::scene::{Camera, Gaussians, Population, ReflectionPlane};
use trgs_render::FrameImages;

/// The least relative rise of the held-out views' L1 when a kept candidate is switched off.
/// Switching a plane off measures how much the model leans on it, not what the model would be
/// without it: a plane that explains little still carries some of the image once trained with
/// it, while training with it (its losses, the perturbation) costs the Gaussians behind it. The
/// bar is set from measurements listed in docs/RESULTS.md ("Planes without masks"): a real
/// facade candidate kept at +0.8% left its model below plain 3DGS; the reflectors found on the
/// synthetic scenes and on a real facade measure several percent.
pub const MIN_L1_GAIN: f64 = 0.02;
/// The least reflection strength `R = R_raw M` of a kept candidate: the 90th percentile over
/// the held-out pixels it is hit at.
pub const MIN_STRENGTH: f64 = 0.05;
/// Every this many training views, one is held out during the trial (none with fewer).
const HOLD_OUT_EVERY: usize = 5;
/// The proposal waits (to its last try) for a model of at least this many times as many
/// Gaussians as the capture has sparse points: a reflector shows as points seen through it, the
/// reflected scene that densification grows behind the glass, which the sparse points of a real
/// capture (surfaces matched across photos) seldom hold.
const GROWN: usize = 2;
/// Primary Gaussians at least this opaque stand for the scene's surfaces in the proposal.
const OPAQUE: f32 = 0.5;

impl TrainingRun {
    /// Propose the candidate planes and put those with evidence on trial (the end of stage 1, or
    /// a later try: [`next_proposal_try`]).
    pub(super) fn propose_planes(&mut self) -> Result<()> {
        let gaussians = self.trainer.gaussians()?;
        let step = self.trainer.step;
        let iterations = self.config().iterations;
        let stage1 = self.trainer.settings.stage1;
        let sparse = self.data.points.len();
        if gaussians.len() < GROWN * sparse
            && let Some(next) = next_proposal_try(step, stage1, iterations)
        {
            self.state.next_proposal = Some(next);
            self.events.push_back(RunEvent::Note(format!(
                "no proposal at step {step}: the model holds {} Gaussians, under {GROWN} times \
                 the {sparse} sparse points, so densification has not yet shown what the glass \
                 reflects; trying again at step {next}",
                gaussians.len()
            )));
            return Ok(());
        }
        let mut points = opaque_centres(&gaussians);
        points.extend(self.data.points.iter().map(|(p, _)| *p));
        let cameras: Vec<Camera> = self.data.train.iter().map(|v| v.camera.clone()).collect();
        let proposal =
            propose_planes(&points, &cameras, &ProposalSettings::default(), &mut self.rng);
        let settings = PlaneInitSettings::default();
        let mut glass = Gaussians::empty(gaussians.sh_degree);
        let (mut planes, mut names, mut on_trial) = (Vec::new(), Vec::new(), Vec::new());
        // Each try's records replace the last's: those of the try that proposed (or of the
        // last) are the run's; log.jsonl keeps every try.
        self.state.candidates.clear();
        for c in &proposal.candidates {
            let index = self.state.candidates.len();
            self.state.candidates.push(CandidateRecord::of(c));
            if let (None, Some(plane)) = (&c.rejected, c.plane) {
                append_glass(&mut glass, &plane, &settings, &mut self.rng);
                planes.push(plane);
                names.push(format!("candidate plane {index}"));
                on_trial.push(index);
            }
        }
        self.log.candidates(step, &self.state.candidates)?;
        self.state.next_proposal =
            if planes.is_empty() { next_proposal_try(step, stage1, iterations) } else { None };
        let summary = format!(
            "{} planar structures, {} points, depth scale {:.3}",
            proposal.candidates.len(),
            points.len(),
            proposal.scale
        );
        if let Some(next) = self.state.next_proposal {
            self.events.push_back(RunEvent::Note(format!(
                "no candidate plane at step {step} ({summary}): trying again at step {next}, \
                 on the model grown by then"
            )));
            return Ok(());
        }
        for (index, record) in self.state.candidates.iter().enumerate() {
            self.events.push_back(RunEvent::Note(record.line(index)));
        }
        if planes.is_empty() {
            self.events.push_back(RunEvent::Note(format!(
                "no candidate plane at step {step} ({summary}): training plain 3DGS"
            )));
            return Ok(());
        }
        if step != stage1 {
            // Stages 2 and 3 start from the step the candidates were found at.
            self.trainer.settings.stage1 = step;
            self.state.stage1_end = Some(step);
            self.events.push_back(RunEvent::Note(format!(
                "stage 1 ends at step {step}, where the proposal found its candidates"
            )));
        }
        let limits = vec![None; planes.len()];
        self.add_planes_with_seeds(&gaussians, &planes, &names, &limits, glass)?;
        let n = self.data.train.len();
        let held_out: Vec<usize> = if n >= HOLD_OUT_EVERY {
            (0..n).filter(|i| i % HOLD_OUT_EVERY == HOLD_OUT_EVERY / 2).collect()
        } else {
            Vec::new()
        };
        self.state.order.retain(|i| !held_out.contains(i));
        let s = &self.trainer.settings;
        let decide_after =
            (s.stage1 + s.stage2 + (iterations / 10).max(1)).min(iterations.saturating_sub(1));
        self.events.push_back(RunEvent::Note(format!(
            "{} candidate planes on trial until step {decide_after}, {} training views held out",
            planes.len(),
            held_out.len()
        )));
        let trial = PlaneTrial { decide_after, held_out, planes: on_trial };
        hold_perturbation_for(&mut self.trainer.settings, &trial);
        self.state.trial = Some(trial);
        Ok(())
    }

    /// Decide the candidates on trial: keep those that pay, remove the others.
    pub(super) fn decide_trial(&mut self) -> Result<()> {
        let Some(trial) = self.state.trial.take() else { return Ok(()) };
        let planes = self.trainer.planes().to_vec();
        let views: Vec<usize> = if trial.held_out.is_empty() {
            (0..self.data.train.len()).collect()
        } else {
            trial.held_out.clone()
        };
        let mut base = 0.0;
        let mut strengths: Vec<Vec<f32>> = vec![Vec::new(); planes.len()];
        for &vi in &views {
            let view = &self.data.train[vi];
            let images = self.trainer.render_with_planes(&planes, &view.camera)?;
            base += view_l1(&images.color, view);
            for (&h, &r) in images.hit.data.iter().zip(&images.strength.data) {
                if let Some(s) = (h as usize).checked_sub(1).and_then(|k| strengths.get_mut(k)) {
                    s.push(r);
                }
            }
        }
        let mut keep = Vec::with_capacity(planes.len());
        for k in 0..planes.len() {
            let mut without = planes.clone();
            without.remove(k);
            let mut off = 0.0;
            for &vi in &views {
                let view = &self.data.train[vi];
                off +=
                    view_l1(&self.trainer.render_with_planes(&without, &view.camera)?.color, view);
            }
            let gain = if base > 0.0 { off / base - 1.0 } else { 0.0 };
            let strength = upper_decile(&mut strengths[k]);
            let kept = gain >= MIN_L1_GAIN && strength >= MIN_STRENGTH;
            let why = verdict(gain, strength, views.len(), trial.held_out.is_empty());
            let index = trial.planes.get(k).copied().unwrap_or(k);
            if let Some(record) = self.state.candidates.get_mut(index) {
                record.held_out_l1_gain = Some(gain);
                record.strength = Some(strength);
                record.kept = kept;
                record.why = why;
                self.events.push_back(RunEvent::Note(record.line(index)));
            }
            keep.push(kept);
        }
        let kept = keep.iter().filter(|&&k| k).count();
        let mut removed = 0;
        if kept < planes.len() {
            // Settled by the caller: the rows read now are those the removal sees.
            let g = self.trainer.gaussians()?;
            let cameras: Vec<&Camera> = self.data.train.iter().map(|v| &v.camera).collect();
            let rows = rows_of_dropped(&g, &planes, &keep, &cameras);
            removed = rows.len();
            self.trainer.remove_planes(&keep, &rows)?;
        }
        if kept > 0 {
            self.fit_kept_to_their_glass()?;
        }
        self.log.candidates(self.trainer.step, &self.state.candidates)?;
        self.events.push_back(RunEvent::Note(format!(
            "{kept} of {} candidate planes kept ({removed} Gaussians that only the others showed \
             removed)",
            planes.len()
        )));
        Ok(())
    }
}

/// Hold the opacity perturbation back until `trial` is decided. It shakes the Gaussians seen
/// through the planes; while a candidate may still be dropped, that only costs the model it would
/// leave behind, and it would blur what switching a candidate off measures.
pub(super) fn hold_perturbation_for(settings: &mut TrainSettings, trial: &PlaneTrial) {
    if let Some(p) = settings.perturb.as_mut() {
        p.from = p.from.max(trial.decide_after + 1);
    }
}

/// The rows (ascending) that only the dropped planes (`keep` false) show: glass Gaussians on a
/// dropped plane ([`owner`]), and primaries that no training camera nearly sees (so only mirrored
/// passes train them: the reflection seeds and what grew from them) whose mirror image about a
/// dropped plane a camera sees through its rectangle, and about no kept plane.
fn rows_of_dropped(
    g: &Gaussians<f32>,
    planes: &[ReflectionPlane],
    keep: &[bool],
    cameras: &[&Camera],
) -> Vec<usize> {
    let shown_by = |k: usize, x: DVec3| {
        let mirrored = reflect_point(&planes[k], x);
        cameras.iter().any(|c| {
            let o = c.pose.centre();
            c.sees(mirrored)
                && ray_rectangle_hit(&planes[k], o, (mirrored - o).normalize()).is_some()
        })
    };
    (0..g.len())
        .filter(|&i| {
            let x = DVec3::from_array(g.means[i].map(f64::from));
            match g.populations[i] {
                Population::Glass => owner(planes, x).is_some_and(|k| !keep[k]),
                Population::Primary => {
                    !cameras.iter().any(|c| c.nearly_sees(x, UNSEEN_MARGIN))
                        && (0..planes.len()).any(|k| !keep[k] && shown_by(k, x))
                        && !(0..planes.len()).any(|k| keep[k] && shown_by(k, x))
                }
            }
        })
        .collect()
}

/// The index of the plane a point at `x` lies on: the nearest along the normal among the planes
/// whose rectangle, grown by a tenth of its size, holds the point's projection.
fn owner(planes: &[ReflectionPlane], x: DVec3) -> Option<usize> {
    let holds = |p: &ReflectionPlane| {
        let d = x - p.centre;
        d.dot(p.axis).abs() <= 0.55 * p.width && d.dot(p.bitangent()).abs() <= 0.55 * p.height
    };
    (0..planes.len()).filter(|&k| holds(&planes[k])).min_by(|&a, &b| {
        planes[a].signed_distance(x).abs().total_cmp(&planes[b].signed_distance(x).abs())
    })
}

impl TrainingRun {
    /// Move each kept plane's rectangle onto its glass: where the training views hit it and the
    /// trained layers say glass ([`glass_pixels`]), taken as each view's glass mask for the
    /// masks' own refinement (`fit::refine_to_masks`). The first rectangle is the see-through
    /// region of the proposal, which the frame and the sight lines past its edges widen. Where
    /// the glass so found pins no rectangle within the refinement's limits, the learned mask
    /// alone is tried.
    fn fit_kept_to_their_glass(&mut self) -> Result<()> {
        let mut planes = self.trainer.planes().to_vec();
        let n = self.data.train.len();
        let stride = n.div_ceil(REFIT_VIEWS).max(1);
        let mut masks: Vec<Vec<(usize, Image<u8>)>> = vec![Vec::new(); planes.len()];
        for vi in (0..n).step_by(stride) {
            let view = &self.data.train[vi];
            let images = self.trainer.render_with_planes(&planes, &view.camera)?;
            for (k, list) in masks.iter_mut().enumerate() {
                let m = glass_pixels(k, &planes[k], &view.camera, &images);
                if m.data.iter().any(|&v| v != NOT_GLASS) {
                    list.push((vi, m));
                }
            }
        }
        let g = self.trainer.gaussians()?;
        let extent = self.data.extent;
        let cameras: Vec<&Camera> = self.data.train.iter().map(|v| &v.camera).collect();
        for (k, list) in masks.iter().enumerate() {
            let before = planes[k];
            let glass = |v: u8| v != NOT_GLASS;
            let text = match refit_to_glass(&before, &cameras, list, &glass, &g, extent, &self.rng)
                .map(|r| (r, "its mask or seen through it"))
                .or_else(|| {
                    let masked = |v: u8| v == MASKED_GLASS;
                    refit_to_glass(&before, &cameras, list, &masked, &g, extent, &self.rng)
                        .map(|r| (r, "its mask alone"))
                }) {
                Some((refit, by)) => {
                    let fit = &refit.fit;
                    planes[k] = fit.plane;
                    let turn = match (refit.turned_deg, refit.outline_deg) {
                        (Some(deg), _) => format!("; turned {deg:.2} deg to the frame around it"),
                        (None, Some(deg)) => {
                            format!("; the frame around it {deg:.2} deg off, not turned to")
                        }
                        (None, None) => String::new(),
                    };
                    format!(
                        "moved onto its glass ({by} in {} views{turn}): {:.2} x {:.2} -> {:.2} x \
                         {:.2}, centre moved {:.3}",
                        refit.views,
                        before.width,
                        before.height,
                        fit.plane.width,
                        fit.plane.height,
                        fit.plane.centre.distance(before.centre)
                    )
                }
                None => format!(
                    "kept as proposed (its glass in {} views pins no rectangle)",
                    list.len()
                ),
            };
            self.events.push_back(RunEvent::Note(format!("kept plane {k}: {text}")));
        }
        self.trainer.move_planes(&planes)
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
}

/// `before` moved onto the pixels of `list` (index into `cameras`, [`glass_pixels`] labels) that
/// `glass` takes: as the masks' planes are initialised ([`fit_to_outline`], then
/// `fit::refine_to_masks`), the plane of the Gaussians `g` around the glass's outline first,
/// where it turns `before` within [`OUTLINE_TURN_DEG`]; the proposal's normal comes
/// from whatever structure it found, which for a pane turned in its opening is a fragment of
/// its frame. From `before` itself where the outline's plane pins no rectangle.
fn refit_to_glass(
    before: &ReflectionPlane,
    cameras: &[&Camera],
    list: &[(usize, Image<u8>)],
    glass: &dyn Fn(u8) -> bool,
    g: &Gaussians<f32>,
    extent: f64,
    rng: &Rng,
) -> Option<GlassRefit> {
    let binary: Vec<(usize, Image<u8>)> = list
        .iter()
        .map(|(vi, m)| {
            let data = m.data.iter().map(|&v| u8::from(glass(v))).collect();
            (*vi, Image { data, ..*m })
        })
        .filter(|(_, m)| m.data.contains(&1))
        .collect();
    let views: Vec<(&Camera, &Image<u8>)> =
        binary.iter().map(|(vi, m)| (cameras[*vi], m)).collect();
    let settings = SilhouetteSettings::default();
    let init = PlaneInitSettings::default();
    // The outline's plane gives the normal alone: the minimum-area box of its inliers also
    // takes in whatever else lies in that plane near the glass (the wall along a hinge), and
    // the refinement counts only the pixels near each view's glass, so it cannot shrink a
    // rectangle that reaches far past them. Fitted on a copy of the run's random stream, so
    // that a plane left as proposed trains as it did before the fit was tried.
    let mut rng = rng.clone();
    let outlined = fit_to_outline(g, &views, 1, before.material, extent, &init, &mut rng)
        .ok()
        .map(|outline| turned_onto(before, &outline))
        .map(|p| (p, p.unit_normal().angle_between(before.unit_normal()).to_degrees()));
    let outline_deg = outlined.map(|(_, deg)| deg);
    let turned =
        outlined.filter(|(_, deg)| OUTLINE_TURN_DEG.contains(deg)).and_then(|(start, deg)| {
            refine_to_masks(&start, &views, 1, &settings).map(|fit| (fit, Some(deg)))
        });
    let (fit, turned_deg) =
        turned.or_else(|| refine_to_masks(before, &views, 1, &settings).map(|fit| (fit, None)))?;
    Some(GlassRefit { fit, views: views.len(), turned_deg, outline_deg })
}

/// `plane`'s rectangle turned into `onto`'s plane: its centre projected onto it, its axis
/// made orthogonal to `onto`'s normal; its size and material as they are.
fn turned_onto(plane: &ReflectionPlane, onto: &ReflectionPlane) -> ReflectionPlane {
    let n = onto.unit_normal();
    let centre = plane.centre - n * (plane.centre - onto.centre).dot(n);
    let mut turned = ReflectionPlane { centre, normal: n, ..*plane };
    turned.orthogonalise_axis();
    turned
}

/// Training views (an even sample) whose learned mask refits the kept planes.
const REFIT_VIEWS: usize = 16;

/// A pixel sees through a plane when its transmission depth is at least this many times the
/// plane's depth there: what it shows lies beyond the plane, not on it (a frame, a wall).
const SEEN_THROUGH_DEPTH: f32 = 1.1;

/// [`glass_pixels`]' labels.
const NOT_GLASS: u8 = 0;
/// The learned mask says glass (M >= 1/2).
const MASKED_GLASS: u8 = 1;
/// The mask does not, but the view sees through the plane ([`SEEN_THROUGH_DEPTH`]).
const SEEN_GLASS: u8 = 2;

/// Where a view's trained layers say plane `k`'s glass is: plane `k` is hit there and either
/// the learned mask says glass ([`MASKED_GLASS`]) or the view sees through the plane
/// ([`SEEN_GLASS`]). The mask alone leaves out glass whose reflection is faint (a dark floor
/// seen through clear glass), where nothing in the loss holds M up, and a rectangle fitted to it
/// shrinks off the pane; the depth alone leaves out a mirror, which nothing is seen through once
/// trained. A frame or a wall inside the first rectangle has neither.
fn glass_pixels(
    k: usize,
    plane: &ReflectionPlane,
    camera: &Camera,
    images: &FrameImages,
) -> Image<u8> {
    let (w, h) = (images.hit.width, images.hit.height);
    let origin = camera.pose.centre();
    let mut out = Image::<u8>::new(w, h, 1);
    for y in 0..h {
        for x in 0..w {
            let p = (y * w + x) as usize;
            if images.hit.data[p] as usize != k + 1 {
                continue;
            }
            // Along a ray of camera-space z = 1, the distance to the plane is its depth.
            let seen_through = ray_rectangle_hit(plane, origin, camera.pixel_ray(x, y))
                .is_some_and(|z| images.depth.data[p] >= SEEN_THROUGH_DEPTH * z as f32);
            out.data[p] = if images.mask.data[p] >= 0.5 {
                MASKED_GLASS
            } else if seen_through {
                SEEN_GLASS
            } else {
                NOT_GLASS
            };
        }
    }
    out
}

/// The 90th percentile of `values` (0 for none): a candidate's strength where it reflects, which
/// the mean would dilute by the wall around the glass that its first rectangle also covers.
fn upper_decile(values: &mut [f32]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let k = (values.len() * 9 / 10).min(values.len() - 1);
    f64::from(*values.select_nth_unstable_by(k, f32::total_cmp).1)
}

/// The centres of the primary Gaussians at least [`OPAQUE`].
fn opaque_centres(g: &Gaussians<f32>) -> Vec<DVec3> {
    let logit = (OPAQUE / (1.0 - OPAQUE)).ln();
    (0..g.len())
        .filter(|&i| g.populations[i] == Population::Primary && g.opacity_logits[i] >= logit)
        .map(|i| DVec3::from_array(g.means[i].map(f64::from)))
        .collect()
}

/// Why a candidate on trial was kept or dropped.
fn verdict(gain: f64, strength: f64, views: usize, on_training_views: bool) -> String {
    let on = if on_training_views { "training" } else { "held-out" };
    let pays = gain >= MIN_L1_GAIN;
    let strong = strength >= MIN_STRENGTH;
    match (pays, strong) {
        (true, true) => format!("switching it off costs {views} {on} views L1"),
        (false, _) => format!(
            "switching it off costs the {views} {on} views less than {:.1}% L1",
            100.0 * MIN_L1_GAIN
        ),
        (true, false) => {
            format!("its reflection is weaker than {MIN_STRENGTH} where the views hit it")
        }
    }
}

/// The mean absolute difference between a render and the view's photo over the pixels the photo
/// covers.
fn view_l1(render: &Image<f32>, view: &View) -> f64 {
    let photo = &view.image;
    let covered = |p: usize| view.covered.as_ref().is_none_or(|c| c.data[p] != 0);
    let (mut sum, mut n) = (0.0f64, 0usize);
    for p in 0..(photo.width as usize * photo.height as usize) {
        if !covered(p) {
            continue;
        }
        for c in 0..3 {
            let photo = f64::from(photo.data[3 * p + c]) / 255.0;
            sum += (f64::from(render.data[3 * p + c]) - photo).abs();
        }
        n += 3;
    }
    if n > 0 { sum / n as f64 } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_perturbation_waits_for_the_trial_to_be_decided() {
        let mut s = TrainSettings::scaled(2000);
        let trial = PlaneTrial { decide_after: 1000, held_out: vec![2], planes: vec![0] };
        hold_perturbation_for(&mut s, &trial);
        assert!(!(0..=1000).any(|t| s.perturbs_at(t)), "none until the decision");
        assert!(s.perturbs_at(1100), "the schedule goes on after it");
        // A resume applies it again; an earlier trial does not move the start back.
        let earlier = PlaneTrial { decide_after: 400, ..trial };
        hold_perturbation_for(&mut s, &earlier);
        assert!(!s.perturbs_at(1000));
    }

    /// A camera 2 in front of a 1 x 1 pane that fills the middle of its 8 x 8 view.
    fn pane_in_view() -> (ReflectionPlane, Camera, FrameImages) {
        use trgs_core::scene::{Intrinsics, Material, Pose};
        let plane =
            ReflectionPlane::new(DVec3::ZERO, DVec3::Z, DVec3::X, 1.0, 1.0, Material::Glass);
        let eye = DVec3::new(0.0, 0.0, 2.0);
        let k = Intrinsics::from_fov_x(60f64.to_radians(), 8, 8);
        let camera = Camera::new("c".to_string(), k, Pose::look_at(eye, DVec3::ZERO, DVec3::Y));
        let f = |v: f32| Image::<f32>::filled(8, 8, 1, v);
        let mut hit = Image::<u32>::new(8, 8, 1);
        for y in 0..8 {
            for x in 0..8 {
                let ray = camera.pixel_ray(x, y);
                let p = (y * 8 + x) as usize;
                hit.data[p] = u32::from(ray_rectangle_hit(&plane, eye, ray).is_some());
            }
        }
        let images = FrameImages {
            color: Image::filled(8, 8, 3, 0.0),
            transmission: Image::filled(8, 8, 3, 0.0),
            depth: f(2.0),
            depth_variance: f(0.0),
            mask: f(0.0),
            alpha: f(1.0),
            hit,
            strength_raw: f(0.0),
            strength: f(0.0),
            reflection: Image::filled(8, 8, 3, 0.0),
            planes: Vec::new(),
        };
        (plane, camera, images)
    }

    #[test]
    fn glass_is_where_the_mask_says_so_or_the_view_sees_through_the_plane() {
        let (plane, camera, mut images) = pane_in_view();
        let inside: Vec<usize> = (0..64).filter(|&p| images.hit.data[p] == 1).collect();
        assert!(inside.len() >= 4 && inside.len() < 64, "{} pixels hit", inside.len());
        let glass = |images: &FrameImages, k: usize, label: u8| -> Vec<usize> {
            let m = glass_pixels(k, &plane, &camera, images);
            (0..64).filter(|&p| m.data[p] == label).collect()
        };
        // On the plane (a frame, a wall) with a low mask: not glass.
        assert_eq!(glass(&images, 0, NOT_GLASS).len(), 64);
        // Seen through with a low mask (faint reflection): glass, where the plane is hit only.
        images.depth = Image::filled(8, 8, 1, 3.0);
        assert_eq!(glass(&images, 0, SEEN_GLASS), inside);
        // On the plane with a high mask (a mirror): glass by the mask.
        images.depth = Image::filled(8, 8, 1, 2.0);
        images.mask = Image::filled(8, 8, 1, 0.9);
        assert_eq!(glass(&images, 0, MASKED_GLASS), inside);
        // Another plane's pixels are not this one's.
        assert_eq!(glass(&images, 1, NOT_GLASS).len(), 64);
    }

    #[test]
    fn the_refit_turns_a_plane_to_the_frame_around_its_glass() {
        use trgs_core::scene::{Intrinsics, Material, Pose};
        // A 1 x 0.8 pane in z = 0 inside a frame of opaque Gaussians 0.1 wide.
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
        let k = Intrinsics::from_fov_x(60f64.to_radians(), 64, 48);
        let cameras: Vec<Camera> = (0..8)
            .map(|i| {
                let a = (-40.0 + 10.0 * f64::from(i)).to_radians();
                let eye = DVec3::new(2.5 * a.sin(), 0.3 * a.cos(), 2.5 * a.cos());
                Camera::new(format!("c{i}"), k, Pose::look_at(eye, DVec3::ZERO, DVec3::Y))
            })
            .collect();
        let list: Vec<(usize, Image<u8>)> = cameras
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let mut m = Image::<u8>::new(64, 48, 1);
                for y in 0..48 {
                    for x in 0..64 {
                        let hit = ray_rectangle_hit(&truth, c.pose.centre(), c.pixel_ray(x, y));
                        m.data[(y * 64 + x) as usize] =
                            if hit.is_some() { MASKED_GLASS } else { NOT_GLASS };
                    }
                }
                (i, m)
            })
            .collect();
        let refs: Vec<&Camera> = cameras.iter().collect();
        let glass = |v: u8| v == MASKED_GLASS;
        let refit = refit_to_glass(&before, &refs, &list, &glass, &g, 1.0, &rng).expect("a fit");
        let p = refit.fit.plane;
        let turned = refit.turned_deg.expect("turned to the frame");
        assert!((turned - 5.0).abs() < 0.5, "turned {turned} deg");
        assert!(p.unit_normal().angle_between(DVec3::Z).to_degrees() < 0.5, "{p:?}");
        assert!(p.centre.distance(truth.centre) < 0.02, "{p:?}");
        assert!((p.width - 1.0).abs() < 0.03 && (p.height - 0.8).abs() < 0.03, "{p:?}");
        // The same frame seen as the proposal turned 30 deg: a wall beside it, not turned to.
        let far = glam::DQuat::from_rotation_y(30f64.to_radians());
        let wall = ReflectionPlane { normal: far * DVec3::Z, axis: far * DVec3::X, ..before };
        let kept = refit_to_glass(&wall, &refs, &list, &glass, &g, 1.0, &rng);
        assert!(kept.is_none_or(|r| r.turned_deg.is_none()));
    }
}
