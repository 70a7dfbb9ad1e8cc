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
//! are removed; a kept one is moved onto its glass (`super::plane_refit`).
use super::candidates::{CandidateRecord, PlaneTrial, next_proposal_try};
use super::refit_wall::Proposed;
use super::{RunEvent, TrainingRun};
use crate::data::View;
use crate::planes::init::{PlaneInitSettings, append_glass};
use crate::planes::reflection_seed::UNSEEN_MARGIN;
use crate::settings::TrainSettings;
use anyhow::Result;
use glam::DVec3;
use trgs_core::Image;
use trgs_core::fit::{ProposalSettings, propose_planes};
use trgs_core::plane_math::{ray_rectangle_hit, reflect_point};
use trgs_core::scene::{Camera, Gaussians, Population, ReflectionPlane};

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
            let records = &self.state.candidates;
            let proposals: Vec<Proposed> = (0..planes.len())
                .filter(|&k| keep[k])
                .map(|k| trial.planes.get(k).copied().unwrap_or(k))
                .map(|i| Proposed::of(records.get(i)))
                .collect();
            self.fit_kept_to_their_glass(&proposals)?;
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
pub(super) fn rows_of_dropped(
    g: &Gaussians<f32>,
    planes: &[ReflectionPlane],
    keep: &[bool],
    cameras: &[&Camera],
) -> Vec<usize> {
    (0..g.len())
        .filter(|&i| {
            let x = DVec3::from_array(g.means[i].map(f64::from));
            match g.populations[i] {
                Population::Glass => owner(planes, x).is_some_and(|k| !keep[k]),
                Population::Primary => {
                    unseen(cameras, x) && {
                        let showing = planes_showing(planes, cameras, x);
                        !showing.is_empty() && showing.iter().all(|&k| !keep[k])
                    }
                }
            }
        })
        .collect()
}

/// For each of `planes`, the rows (ascending) of the primaries that only it shows: no training
/// camera nearly sees them, and a camera sees their mirror image about that plane through its
/// rectangle, and about no other plane. They are trained only through its mirrored pass.
pub(super) fn rows_only_shown_by_each(
    g: &Gaussians<f32>,
    planes: &[ReflectionPlane],
    cameras: &[&Camera],
) -> Vec<Vec<usize>> {
    let mut rows = vec![Vec::new(); planes.len()];
    for i in (0..g.len()).filter(|&i| g.populations[i] == Population::Primary) {
        let x = DVec3::from_array(g.means[i].map(f64::from));
        if unseen(cameras, x)
            && let [k] = planes_showing(planes, cameras, x)[..]
        {
            rows[k].push(i);
        }
    }
    rows
}

/// Whether no camera of `cameras` nearly sees a point at `x` ([`UNSEEN_MARGIN`]).
fn unseen(cameras: &[&Camera], x: DVec3) -> bool {
    !cameras.iter().any(|c| c.nearly_sees(x, UNSEEN_MARGIN))
}

/// The planes (indices into `planes`) through whose rectangle a camera of `cameras` sees the
/// mirror image of a point at `x`.
fn planes_showing(planes: &[ReflectionPlane], cameras: &[&Camera], x: DVec3) -> Vec<usize> {
    (0..planes.len())
        .filter(|&k| {
            let mirrored = reflect_point(&planes[k], x);
            cameras.iter().any(|c| {
                let o = c.pose.centre();
                c.sees(mirrored)
                    && ray_rectangle_hit(&planes[k], o, (mirrored - o).normalize()).is_some()
            })
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

/// The 90th percentile of `values` (0 for none): a candidate's strength where it reflects, which
/// the mean would dilute by the wall around the glass that its first rectangle also covers.
fn upper_decile(values: &mut [f32]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let k = (values.len() * 9 / 10).min(values.len() - 1);
    f64::from(*values.select_nth_unstable_by(k, f32::total_cmp).1)
}

/// The centres of the primary Gaussians at least [`OPAQUE`]: with the sparse points, what the
/// proposal sees of the scene (also `examples/propose_probe`).
pub fn opaque_centres(g: &Gaussians<f32>) -> Vec<DVec3> {
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
    use trgs_core::scene::{Intrinsics, Material, Pose};

    /// Seen directly: the camera's own. Behind the camera and seen mirrored through one pane's
    /// rectangle: that pane's alone. Mirrored past both panes, or a glass Gaussian: no pane's.
    #[test]
    fn what_only_one_plane_shows_is_what_only_its_mirrored_pass_trains() {
        let k = Intrinsics::from_fov_x(1.6, 64, 48);
        let eye = Pose::look_at(DVec3::new(0.0, 0.0, -3.0), DVec3::ZERO, DVec3::Y);
        let camera = Camera::new("c", k, eye);
        let pane = |x: f64| {
            let centre = DVec3::new(x, 0.0, 0.0);
            ReflectionPlane::new(centre, DVec3::NEG_Z, DVec3::X, 2.0, 2.0, Material::Glass)
        };
        let planes = [pane(0.0), pane(2.2)];
        let at = [
            (DVec3::new(0.0, 0.0, -1.0), Population::Primary), // seen directly
            (DVec3::new(0.0, 0.0, -5.0), Population::Primary), // mirrored through the first
            (DVec3::new(4.8, 0.0, -5.0), Population::Primary), // through the second (x 1.8)
            (DVec3::new(0.0, 40.0, -5.0), Population::Primary), // past both
            (DVec3::new(0.0, 0.0, -5.0), Population::Glass),
        ];
        let mut g = Gaussians::zeros(at.len(), 0);
        for (i, (x, population)) in at.iter().enumerate() {
            g.means[i] = x.to_array().map(|v| v as f32);
            g.populations[i] = *population;
        }
        let cameras = [&camera];
        assert_eq!(rows_only_shown_by_each(&g, &planes, &cameras), vec![vec![1], vec![2]]);
        assert_eq!(rows_of_dropped(&g, &planes, &[true, false], &cameras), vec![2]);
    }

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
}
