//! The family of glass scenes trgs is measured on: the generator's settings that decide how hard
//! a scene is, as named members chosen before any tuning ([`members`]) and as members drawn from
//! a seed ([`drawn`]) for checks on scenes nobody tuned on.
//!
//! What makes a member hard is what its photos leave out or make faint: without room views the
//! camera room (and its light panels) is only ever seen in the glass; a low R0 makes the
//! reflection faint; a mirror without planes.json starts as glass; a turned pane or a walk-by
//! sees the glass obliquely. `bench --family` trains TR-Gaussians and plain 3DGS on them.
use std::path::Path;

use super::{Backdrop, CameraPath, PaneKind, SyntheticConfig, generate, write_dataset};
use trgs_core::io::FormatError;
use trgs_core::rng::Rng;

/// One scene of the family.
#[derive(Clone, Debug, PartialEq)]
pub struct FamilyMember {
    pub name: String,
    /// What the member tests, in a few words.
    pub about: String,
    pub config: SyntheticConfig,
    /// Whether the scene folder has a planes.json naming each label's material; without one,
    /// every pane starts as glass and a mirror has to be learnt.
    pub materials: bool,
}

impl FamilyMember {
    /// Generate the scene and write its folder (see [`write_dataset`]), without planes.json
    /// when the member has no materials file.
    pub fn write(&self, dir: &Path) -> Result<(), FormatError> {
        write_dataset(&generate(&self.config), dir)?;
        let materials = dir.join("planes.json");
        if !self.materials && materials.exists() {
            std::fs::remove_file(&materials).map_err(|e| FormatError::io(&materials, &e))?;
        }
        Ok(())
    }

    /// The truth's base reflectance of pane `k`.
    pub fn r0(&self, k: usize) -> f64 {
        self.config.r0.unwrap_or(match self.config.panes[k] {
            PaneKind::Glass => super::GLASS_R0,
            PaneKind::Mirror => super::MIRROR_R0,
        })
    }
}

/// Loop views of every member (every 8th a test view) unless it says otherwise.
const VIEWS: usize = 48;

fn member(name: &str, about: &str, config: SyntheticConfig) -> FamilyMember {
    FamilyMember { name: name.into(), about: about.into(), config, materials: true }
}

/// The eight members of issue 38's table, fixed before tuning. Each differs from trgs's own demo
/// scenes in what makes separating the layers hard.
pub fn members() -> Vec<FamilyMember> {
    let base = SyntheticConfig { views: VIEWS, room_views: 0, ..SyntheticConfig::default() };
    vec![
        member(
            "arc-lights",
            "arc of 64 views, no room views, 2 light panels seen only in the glass, R0 0.12",
            SyntheticConfig {
                views: 64,
                masked_views: 8,
                path: CameraPath::Arc,
                reflected_lights: 2,
                r0: Some(0.12),
                seed: 11,
                ..base.clone()
            },
        ),
        FamilyMember {
            materials: false,
            ..member(
                "mirror-unlabelled",
                "a mirror (R0 0.98) and no planes.json, so it starts as glass; 1 light panel",
                SyntheticConfig {
                    panes: vec![PaneKind::Mirror],
                    r0: Some(0.98),
                    reflected_lights: 1,
                    seed: 12,
                    ..base.clone()
                },
            )
        },
        member(
            "clear-glass",
            "shop window of clear glass (R0 0.05), with room views",
            SyntheticConfig {
                backdrop: Backdrop::Showcase,
                r0: Some(0.05),
                room_views: 8,
                seed: 13,
                ..base.clone()
            },
        ),
        member(
            "two-turned-panes",
            "two panes, the right one turned 20 degrees (ajar), 1 light panel",
            SyntheticConfig {
                panes: vec![PaneKind::Glass, PaneKind::Glass],
                pane_turn_deg: vec![0.0, 20.0],
                reflected_lights: 1,
                seed: 14,
                ..base.clone()
            },
        ),
        member(
            "walk-by",
            "walking past a shop window (R0 0.1), 2 light panels",
            SyntheticConfig {
                backdrop: Backdrop::Showcase,
                path: CameraPath::WalkBy,
                r0: Some(0.1),
                reflected_lights: 2,
                seed: 15,
                ..base.clone()
            },
        ),
        member(
            "close-ups-night",
            "close-ups of a window onto a dim room (behind gain 0.3)",
            SyntheticConfig {
                path: CameraPath::CloseUp,
                behind_gain: 0.3,
                seed: 16,
                ..base.clone()
            },
        ),
        member(
            "bright-behind",
            "shop window lit as brightly as the room (faint reflection, R0 0.08), room views",
            SyntheticConfig {
                backdrop: Backdrop::Showcase,
                behind_gain: 1.0,
                r0: Some(0.08),
                room_views: 8,
                seed: 17,
                ..base.clone()
            },
        ),
        member(
            "large-pane-lights",
            "a 1.4x larger window (R0 0.3), dim room behind, 3 light panels, arc",
            SyntheticConfig {
                path: CameraPath::Arc,
                pane_scale: 1.4,
                behind_gain: 0.4,
                r0: Some(0.3),
                reflected_lights: 3,
                seed: 18,
                ..base
            },
        ),
    ]
}

/// A member drawn from `seed`: every setting of the family at random within its range.
pub fn drawn(seed: u64) -> FamilyMember {
    let mut rng = Rng::new(seed ^ 0xFA_11_u64);
    let mut pick = |n: usize| rng.below(n);
    let backdrop = [Backdrop::Room, Backdrop::Showcase][pick(2)];
    let path =
        [CameraPath::Loop, CameraPath::Arc, CameraPath::WalkBy, CameraPath::CloseUp][pick(4)];
    let room_views = [0, 8][pick(2)];
    let reflected_lights = pick(4);
    let panes = 1 + usize::from(pick(10) < 3);
    let mirror = pick(5) == 0;
    let materials = pick(10) < 7;
    let kind = if mirror { PaneKind::Mirror } else { PaneKind::Glass };
    let mut rng = Rng::new(seed ^ 0xFA_12_u64);
    // Glass from clear (0.04) to strongly reflecting (0.35), evenly in log R0; mirrors 0.85-0.98.
    let r0 = if mirror {
        rng.range(0.85, 0.98)
    } else {
        (0.04f64.ln() + rng.uniform() * (0.35f64 / 0.04).ln()).exp()
    };
    let pane_turn_deg = (0..panes)
        .map(|_| if rng.uniform() < 0.5 { rng.range(-20.0, 20.0) } else { 0.0 })
        .collect();
    let config = SyntheticConfig {
        views: VIEWS,
        room_views,
        seed,
        panes: vec![kind; panes],
        backdrop,
        behind_gain: rng.range(0.3, 1.0),
        r0: Some(r0),
        pane_scale: rng.range(0.8, 1.3),
        pane_turn_deg,
        reflected_lights,
        path,
        ..SyntheticConfig::default()
    };
    let about = format!(
        "drawn from seed {seed}: {panes} {kind:?} pane(s), R0 {r0:.3}, {backdrop:?}, {path:?}, \
         {room_views} room views, {reflected_lights} lights{}",
        if materials { "" } else { ", no planes.json" }
    );
    FamilyMember { name: format!("drawn-{seed}"), about, config, materials }
}

/// The member called `name`: one of [`members`], or `drawn-<seed>`.
pub fn by_name(name: &str) -> Option<FamilyMember> {
    if let Some(seed) = name.strip_prefix("drawn-") {
        return seed.parse().ok().map(drawn);
    }
    members().into_iter().find(|m| m.name == name)
}
