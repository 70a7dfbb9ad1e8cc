//! What a kept plane's proposal tells its refit (`super::plane_refit`): a point of the
//! structure it was found on, and the wall's opening it was found turned in.
//!
//! The proposal hands the sight lines through a wall's opening to a structure turned in it
//! (`trgs_core::fit::openings`): a pane ajar. The virtual Gaussians behind a pane, the
//! reflected scene, can form such a structure too; the wall's own candidate is then left
//! without its opening, and the trial keeps the turned one (walk-by, docs/RESULTS.md, "Planes
//! without masks"). The trained layers tell the two apart: the glass of a pane turned in its
//! opening is framed by the pane's own frame, turned with it, while the glass seen over a
//! structure of the reflected scene is framed by the wall ([`WallFrame`]). Such a plane is
//! moved into the opening ([`into_opening`]) and starts over there
//! ([`TrainingRun::start_over_in_openings`]).
use super::candidates::CandidateRecord;
use super::plane_trial::rows_of_dropped;
use super::{RunEvent, TrainingRun};
use crate::planes::init::{PlaneInitSettings, append_glass};
use anyhow::Result;
use glam::DVec3;
use trgs_core::scene::{Camera, Gaussians, ReflectionPlane};

/// What a kept plane's proposal says of where its glass lies.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Proposed {
    /// A point of its structure's plane.
    pub point: Option<DVec3>,
    /// The opening of a wall it was found turned in, in the wall's plane.
    pub opening: Option<ReflectionPlane>,
}

impl Proposed {
    /// What a candidate's record says.
    pub fn of(record: Option<&CandidateRecord>) -> Self {
        Self {
            point: record.and_then(|r| r.centre).map(DVec3::from_array),
            opening: record.and_then(|r| r.opening).map(|o| o.plane()),
        }
    }
}

/// How many of `outline`, the Gaussians around the outline of the glass of `pane` in the views
/// (`planes::init::outline_gaussians`), lie within `threshold` of the plane of the wall whose
/// opening `pane` was found turned in (`opening`), and of `pane`'s own plane. Around the glass
/// of a pane turned in its opening lies its own frame, turned with it (and the wall along a
/// hinge, where the two planes meet); around glass that a structure of the reflected scene
/// behind it took lies the wall, which then frames it ([`WallFrame::frames`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct WallFrame {
    pub on_wall: usize,
    pub on_pane: usize,
}

impl WallFrame {
    pub fn count(
        opening: &ReflectionPlane,
        pane: &ReflectionPlane,
        outline: &[DVec3],
        threshold: f64,
    ) -> Self {
        let near = |p: &ReflectionPlane| {
            outline.iter().filter(|&&x| p.signed_distance(x).abs() <= threshold).count()
        };
        Self { on_wall: near(opening), on_pane: near(pane) }
    }

    /// Whether more of the outline lies in the wall than in the pane.
    pub fn frames(self) -> bool {
        self.on_wall > self.on_pane
    }
}

/// `pane` moved to `opening`: the opening's rectangle, facing the side `pane` faces, with the
/// pane's material and learned R0.
pub(super) fn into_opening(pane: &ReflectionPlane, opening: &ReflectionPlane) -> ReflectionPlane {
    let n = opening.unit_normal();
    let normal = if n.dot(pane.unit_normal()) < 0.0 { -n } else { n };
    ReflectionPlane { normal, material: pane.material, r0_logit: pane.r0_logit, ..*opening }
}

impl TrainingRun {
    /// The kept planes `moved` (indices into the trainer's planes, which stand in their walls'
    /// openings) start over there as a new candidate does: what they were trained as on
    /// trial (`trained`: the structure behind the glass) leaves its glass Gaussians and the
    /// Gaussians only its mirrored pass showed, which were seeded for it and mirror what it
    /// reflected ([`rows_of_dropped`]); each gets glass Gaussians over its opening and
    /// reflection seeds. They are last among the planes after.
    pub(super) fn start_over_in_openings(
        &mut self,
        trained: &[ReflectionPlane],
        moved: &[usize],
    ) -> Result<()> {
        let now = self.trainer.planes().to_vec();
        let g = self.trainer.gaussians()?;
        let cameras: Vec<&Camera> = self.data.train.iter().map(|v| &v.camera).collect();
        let mut both = now.clone();
        both.extend(moved.iter().map(|&k| trained[k]));
        let mut keep = vec![true; now.len()];
        keep.resize(both.len(), false);
        let rows = rows_of_dropped(&g, &both, &keep, &cameras);
        let stays: Vec<bool> = (0..now.len()).map(|k| !moved.contains(&k)).collect();
        self.trainer.remove_planes(&stays, &rows)?;
        self.events.push_back(RunEvent::Note(format!(
            "kept planes {moved:?} start over in their openings ({} Gaussians that only the \
             structures they stood on showed removed)",
            rows.len()
        )));
        let g = self.trainer.gaussians()?;
        let planes: Vec<ReflectionPlane> = moved.iter().map(|&k| now[k]).collect();
        let mut glass = Gaussians::empty(g.sh_degree);
        for plane in &planes {
            append_glass(&mut glass, plane, &PlaneInitSettings::default(), &mut self.rng);
        }
        let names: Vec<String> = moved.iter().map(|k| format!("kept plane {k}")).collect();
        self.add_planes_with_seeds(&g, &planes, &names, &vec![None; planes.len()], glass)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use trgs_core::scene::Material;

    fn pane(centre: DVec3, turn_deg: f64) -> ReflectionPlane {
        let q = glam::DQuat::from_rotation_y(turn_deg.to_radians());
        ReflectionPlane::new(centre, q * DVec3::Z, q * DVec3::X, 1.2, 0.9, Material::Glass)
    }

    #[test]
    fn the_wall_frames_the_glass_where_more_of_its_outline_lies_in_the_wall_than_in_the_pane() {
        let opening = pane(DVec3::new(0.3, 0.0, 0.0), 180.0);
        let turned = pane(DVec3::new(0.2, 0.0, -0.4), 40.0);
        let on = |p: &ReflectionPlane, n: usize| -> Vec<DVec3> {
            (0..n).map(|i| p.centre + p.axis * (0.1 * i as f64 - 0.5)).collect()
        };
        let wall_ring = on(&opening, 8);
        let pane_ring = on(&turned, 5);
        let outline: Vec<DVec3> = wall_ring.iter().chain(&pane_ring).copied().collect();
        assert!(WallFrame::count(&opening, &turned, &outline, 0.01).frames());
        let outline: Vec<DVec3> = wall_ring[..3].iter().chain(&pane_ring).copied().collect();
        let counts = WallFrame::count(&opening, &turned, &outline, 0.01);
        assert_eq!(counts, WallFrame { on_wall: 3, on_pane: 5 });
        assert!(!counts.frames());
        assert!(!WallFrame::count(&opening, &turned, &[], 0.01).frames());
    }

    #[test]
    fn a_pane_moved_into_its_opening_faces_its_way_and_keeps_its_material() {
        let opening = pane(DVec3::new(0.3, 0.1, 0.0), 180.0);
        let mut turned = pane(DVec3::new(0.2, 0.0, -0.4), 40.0);
        turned.material = Material::Mirror;
        turned.r0_logit = 0.7;
        let p = into_opening(&turned, &opening);
        assert!(p.unit_normal().distance(DVec3::Z) < 1e-12, "{p:?}");
        assert_eq!((p.centre, p.axis, p.width, p.height), (opening.centre, opening.axis, 1.2, 0.9));
        assert_eq!((p.material, p.r0_logit), (Material::Mirror, 0.7));
    }

    #[test]
    fn a_kept_plane_turned_in_a_walls_opening_carries_it() {
        let json = serde_json::json!({"centre": [0.5, 0.0, 1.2], "normal": [0.6, 0.0, -0.8],
            "axis": null, "size": null, "support": 3, "seen_through": 0, "seen_fraction": 0.0,
            "cameras_in_front": 1.0, "proposed": true, "held_out_l1_gain": null,
            "strength": null, "kept": true, "why": "", "opening_of": 0, "opening": {
                "centre": [0.4, 0.0, 1.0], "normal": [0.0, 0.0, -1.0], "axis": [1.0, 0.0, 0.0],
                "size": [1.0, 0.8]}});
        let record: CandidateRecord = serde_json::from_value(json).expect("a record");
        let proposed = Proposed::of(Some(&record));
        assert_eq!(proposed.point, Some(DVec3::new(0.5, 0.0, 1.2)));
        let opening = proposed.opening.expect("its opening");
        assert_eq!(
            (opening.centre, opening.width, opening.height),
            (DVec3::new(0.4, 0.0, 1.0), 1.0, 0.8)
        );
        assert_eq!(opening.unit_normal(), DVec3::NEG_Z);
        assert_eq!(Proposed::of(None), Proposed::default());
    }
}
