//! The record of a `--planes auto` run's candidate planes and of the trial they are on (in the
//! checkpoint, log.jsonl and metrics.json); `plane_trial` proposes and decides them.
use glam::DVec3;
use serde::{Deserialize, Serialize};
use trgs_core::fit::PlaneCandidate;
use trgs_core::scene::{Material, ReflectionPlane};

/// What became of one candidate, for the log, metrics.json and the `train` output.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CandidateRecord {
    /// The plane over the see-through region (None where none was found).
    pub centre: Option<[f64; 3]>,
    pub normal: Option<[f64; 3]>,
    /// In-plane, along the width.
    pub axis: Option<[f64; 3]>,
    pub size: Option<[f64; 2]>,
    /// Points on the structure and seen through it; their fraction; the cameras in front.
    pub support: usize,
    pub seen_through: usize,
    pub seen_fraction: f64,
    pub cameras_in_front: f64,
    /// How flat its structure is over its hull (`trgs_core::fit::PlaneCandidate::planarity`);
    /// absent in records from before.
    #[serde(default)]
    pub planarity: Option<f64>,
    /// The same over the cells it holds points in (`PlaneCandidate::wall_planarity`).
    #[serde(default)]
    pub wall_planarity: Option<f64>,
    /// Put on trial (the proposal's evidence sufficed).
    pub proposed: bool,
    /// On trial: the relative rise of the held-out L1 when it is switched off, and its mean
    /// reflection strength where it is hit.
    pub held_out_l1_gain: Option<f64>,
    pub strength: Option<f64>,
    pub kept: bool,
    /// Why it was not proposed, or why it was kept or dropped.
    pub why: String,
    /// The candidate in an opening of which it is turned, whose sight lines there it took
    /// (`trgs_core::fit::PlaneCandidate::opening_of`); absent in records from before.
    #[serde(default)]
    pub opening_of: Option<usize>,
    /// That opening as a rectangle in the wall's plane (`PlaneCandidate::opening`), where its
    /// refit moves a plane whose glass the wall frames (`super::refit_wall`); absent in records
    /// from before.
    #[serde(default)]
    pub opening: Option<RecordedRectangle>,
}

/// A rectangle of a [`CandidateRecord`]: its centre, unit normal, axis (along its width) and
/// size (width, height).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RecordedRectangle {
    pub centre: [f64; 3],
    pub normal: [f64; 3],
    pub axis: [f64; 3],
    pub size: [f64; 2],
}

impl RecordedRectangle {
    fn of(p: &ReflectionPlane) -> Self {
        Self {
            centre: p.centre.to_array(),
            normal: p.unit_normal().to_array(),
            axis: p.axis.to_array(),
            size: [p.width, p.height],
        }
    }

    /// The glass plane over it.
    pub fn plane(&self) -> ReflectionPlane {
        let [w, h] = self.size;
        let v = DVec3::from_array;
        ReflectionPlane::new(v(self.centre), v(self.normal), v(self.axis), w, h, Material::Glass)
    }
}

impl CandidateRecord {
    pub(super) fn of(c: &PlaneCandidate) -> Self {
        Self {
            centre: c.plane.map(|p| p.centre.to_array()),
            normal: c.plane.map(|p| p.unit_normal().to_array()),
            axis: c.plane.map(|p| p.axis.to_array()),
            size: c.plane.map(|p| [p.width, p.height]),
            support: c.support,
            seen_through: c.seen_through,
            seen_fraction: c.seen_fraction,
            cameras_in_front: c.cameras_in_front,
            planarity: Some(c.planarity),
            wall_planarity: Some(c.wall_planarity),
            proposed: c.rejected.is_none(),
            held_out_l1_gain: None,
            strength: None,
            kept: false,
            why: match (&c.rejected, c.opening_of) {
                (Some(why), _) => why.clone(),
                (None, Some(wall)) => format!(
                    "on trial, over the opening of candidate {wall} it is turned in (the sight \
                     lines through that opening are its)"
                ),
                (None, None) => "on trial".into(),
            },
            opening_of: c.opening_of,
            opening: c.opening.as_ref().map(RecordedRectangle::of),
        }
    }

    /// One line for the `train` output.
    pub fn line(&self, index: usize) -> String {
        let at = match (self.centre, self.normal, self.size) {
            (Some(c), Some(n), Some([w, h])) => format!(
                " at ({:.2}, {:.2}, {:.2}) facing ({:.2}, {:.2}, {:.2}), {w:.2} x {h:.2}",
                c[0], c[1], c[2], n[0], n[1], n[2]
            ),
            _ => String::new(),
        };
        let trial = match (self.held_out_l1_gain, self.strength) {
            (Some(g), Some(r)) => {
                format!("; off: held-out L1 {:+.2}%, strength {r:.3}", 100.0 * g)
            }
            _ => String::new(),
        };
        let verdict = match (self.proposed, self.held_out_l1_gain.is_some(), self.kept) {
            (false, _, _) => format!("not proposed: {}", self.why),
            (true, false, _) => self.why.clone(),
            (true, true, true) => format!("kept: {}", self.why),
            (true, true, false) => format!("dropped: {}", self.why),
        };
        let flat = match (self.planarity, self.wall_planarity) {
            (Some(p), Some(w)) => {
                format!(" ({:.0}% flat, {:.0}% over its own cells)", 100.0 * p, 100.0 * w)
            }
            _ => String::new(),
        };
        format!(
            "candidate plane {index}{at}: {} points on it{flat}, {} seen through ({:.1}%), {:.0}% \
             of the cameras in front{trial}: {verdict}",
            self.support,
            self.seen_through,
            100.0 * self.seen_fraction,
            100.0 * self.cameras_in_front,
        )
    }
}

/// The candidates on trial, kept in the run's checkpoint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlaneTrial {
    /// The step after which the candidates are decided.
    pub decide_after: u32,
    /// Training views left out of the steps until then (their indices).
    pub held_out: Vec<usize>,
    /// The candidate (its index in the run's records) of each of the trainer's planes.
    pub planes: Vec<usize>,
}

/// The step the proposal is tried at next after a try at `step` found no candidate: one
/// stage-1 length (`stage1`) later, while at least half the run is left for the planes' stages
/// (None: no more tries, the run trains plain 3DGS). A short run's model at the end of its
/// stage 1 has been densified once or twice, from sparse points alone on a real capture: too
/// few surfaces to show a reflector that the grown model shows. A try that finds candidates
/// ends stage 1 there, so that stages 2 and 3 keep their lengths.
pub fn next_proposal_try(step: u32, stage1: u32, iterations: u32) -> Option<u32> {
    let next = step.checked_add(stage1.max(1))?;
    (next <= iterations / 2).then_some(next)
}

#[cfg(test)]
mod tests {
    use super::{CandidateRecord, next_proposal_try};

    #[test]
    fn a_record_from_before_the_openings_reads_as_turned_in_none_and_without_planarity() {
        let old = r#"{"centre": null, "normal": null, "axis": null, "size": null, "support": 3,
            "seen_through": 0, "seen_fraction": 0.0, "cameras_in_front": 1.0, "proposed": false,
            "held_out_l1_gain": null, "strength": null, "kept": false, "why": "too few"}"#;
        let record: CandidateRecord = serde_json::from_str(old).expect("an older record");
        assert_eq!((record.opening_of, record.opening), (None, None));
        assert_eq!((record.planarity, record.wall_planarity), (None, None));
        assert!(!record.line(0).contains("flat"), "{}", record.line(0));
        assert_eq!(record.why, "too few");
    }

    #[test]
    fn a_record_reads_back_as_the_outline_the_viewer_draws() {
        let record = CandidateRecord {
            centre: Some([0.5, 1.0, -2.0]),
            normal: Some([0.0, 0.0, 1.0]),
            axis: Some([1.0, 0.0, 0.0]),
            size: Some([2.4, 1.4]),
            support: 120,
            seen_through: 40,
            seen_fraction: 0.25,
            cameras_in_front: 1.0,
            planarity: Some(0.38),
            wall_planarity: Some(0.56),
            proposed: true,
            held_out_l1_gain: Some(0.0007),
            strength: Some(0.07),
            kept: false,
            why: "dropped".into(),
            opening_of: None,
            opening: None,
        };
        let text =
            serde_json::to_string(&serde_json::json!({"candidates": [record]})).expect("json");
        let outline = &trgs_core::io::RunMetrics::parse(&text).expect("metrics").candidates[0];
        assert_eq!(outline.centre, record.centre);
        assert_eq!(outline.normal, record.normal);
        assert_eq!(outline.axis, record.axis);
        assert_eq!(outline.size, record.size);
        assert_eq!((outline.proposed, outline.kept), (true, false));
    }

    #[test]
    fn the_proposal_is_tried_every_stage1_length_up_to_half_the_run() {
        // 2000 steps: stage 1 ends at 200; tries at 200, 400, ..., 1000.
        let (mut at, mut tries) = (200, vec![200]);
        while let Some(next) = next_proposal_try(at, 200, 2000) {
            tries.push(next);
            at = next;
        }
        assert_eq!(tries, [200, 400, 600, 800, 1000]);
        // The paper's 30000 steps: 3000, 6000, ..., 15000.
        assert_eq!(next_proposal_try(12_000, 3000, 30_000), Some(15_000));
        assert_eq!(next_proposal_try(15_000, 3000, 30_000), None);
        // A degenerate stage 1 still moves on, and a short run tries once.
        assert_eq!(next_proposal_try(0, 0, 10), Some(1));
        assert_eq!(next_proposal_try(2, 2, 4), None);
        assert_eq!(next_proposal_try(u32::MAX - 1, 5, u32::MAX), None);
    }
}
