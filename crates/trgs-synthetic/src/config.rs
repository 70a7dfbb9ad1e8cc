//! The settings of a synthetic scene ([`SyntheticConfig`]): its panes and what they are made
//! of, what stands behind them, the camera path and the lens the photos are taken through.
use trgs_core::lens::Distortion;

/// What a pane is made of; the truth's base reflectance follows from it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PaneKind {
    /// Window glass, R0 = [`GLASS_R0`].
    Glass,
    /// A mirror on the wall, R0 = [`MIRROR_R0`].
    Mirror,
}

/// Base reflectance of the truth glass. Real glass has about 0.04; 0.2 (trgs's initial value)
/// makes the reflection clearly visible, so that separating it is both necessary for a good fit
/// and well-posed at 256x192 with 8-bit images.
pub const GLASS_R0: f64 = 0.2;

/// Base reflectance of the truth mirror: a little below trgs's initial 0.99, so that it has to be
/// learnt, and the wall behind still shows faintly (transmission) as with a real silvered mirror.
pub const MIRROR_R0: f64 = 0.95;

/// What stands behind the pane wall.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Backdrop {
    /// A second room, 4.5 m deep, behind a 1.6 m x 1.0 m window (about 18% of a loop view's
    /// pixels): a floor, walls and objects 1 to 4.5 m behind the pane, seen from a narrow range
    /// of angles, so the transmitted view is itself hard to reconstruct.
    #[default]
    Room,
    /// A shop window: one 2.4 m x 1.4 m pane (about 40% of a loop view's pixels) in front of a
    /// display 1.6 m deep whose objects stand on a plinth 0.15 to 1.45 m behind the glass, as in
    /// the paper's bookcase scenes. The transmitted view is easy; what is hard is the
    /// reflection, which lies at a very different depth over much of the image.
    Showcase,
}

/// Where the scene is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Setting {
    /// A camera room in front of a window wall (the built-in scenes and the scene family): the
    /// panes, backdrop, path and light panels of the config apply.
    #[default]
    Room,
    /// A street of shop windows, 24 m long, walked along twice ([`SyntheticConfig::street`]):
    /// for blocks, seams and panes that two blocks share. The panes take the street's fixed
    /// slots in order (at most five); backdrop, path, pane size and turn, room views and light
    /// panels do not apply.
    Street,
}

/// Settings of [`generate`](fn@super::generate).
#[derive(Clone, Debug, PartialEq)]
pub struct SyntheticConfig {
    pub width: u32,
    pub height: u32,
    /// Number of views along the camera loop (every 8th a test view).
    pub views: usize,
    /// Training views after the loop that look back into the camera room (`view_<views>.png`
    /// on); no masks, never test views.
    pub room_views: usize,
    /// Varies textures (noise, panel colours) and the sparse points; the geometry is fixed.
    pub seed: u64,
    /// The panes, left to right; empty gives a scene without glass (and no masks or planes).
    pub panes: Vec<PaneKind>,
    /// How many training views get a glass mask (spread over the loop).
    pub masked_views: usize,
    /// How many sparse "SfM" points to produce.
    pub sparse_points: usize,
    /// Light level of the room behind the glass relative to the camera room:
    /// [`DAY_BEHIND_GAIN`] by default, [`NIGHT_BEHIND_GAIN`] for [`SyntheticConfig::night`].
    pub behind_gain: f64,
    /// What stands behind the pane wall.
    pub backdrop: Backdrop,
    /// Base reflectance of every pane; `None`: [`GLASS_R0`] for glass, [`MIRROR_R0`] for mirrors.
    pub r0: Option<f64>,
    /// Multiplies the panes' width and height (each is limited to what the wall can hold).
    pub pane_scale: f64,
    /// Turn of each pane about its vertical centre line, in degrees (missing entries: 0): a
    /// window left ajar, a mirror hung at an angle. Positive turns the pane's right edge away
    /// from the cameras.
    pub pane_turn_deg: Vec<f64>,
    /// Bright light panels on the wall behind the cameras (at most four): what the glass
    /// reflects most strongly, and, without room views, never seen directly.
    pub reflected_lights: usize,
    /// How the cameras move in front of the glass.
    pub path: CameraPath,
    /// The lens the photos are taken through (their COLMAP model).
    pub lens: SyntheticLens,
    /// A room or a street.
    pub setting: Setting,
}

/// The lens of the synthetic photos: a pinhole, or a distorting lens whose photos the loader must
/// undistort (the scale fixture's camera model of choice). The distorting lenses keep the
/// pinhole's focal length, so their photos see a little more of the room.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SyntheticLens {
    #[default]
    Pinhole,
    /// OPENCV with a phone main camera's mild barrel distortion and a little decentring.
    Opencv,
    /// OPENCV_FISHEYE, an action camera's equidistant lens.
    OpencvFisheye,
}

impl SyntheticLens {
    pub const ALL: [SyntheticLens; 3] = [Self::Pinhole, Self::Opencv, Self::OpencvFisheye];

    /// The lens's distortion; None for the pinhole.
    pub fn distortion(self) -> Option<Distortion> {
        match self {
            Self::Pinhole => None,
            Self::Opencv => Some(Distortion::RadialTangential {
                k: [-0.12, 0.03, 0.0, 0.0, 0.0, 0.0],
                p: [5e-4, -3e-4],
            }),
            Self::OpencvFisheye => Some(Distortion::Fisheye { k: [0.03, -0.005, 0.001, 0.0] }),
        }
    }

    /// COLMAP's name of the model the photos are written with.
    pub fn colmap_model(self) -> &'static str {
        match self {
            Self::Pinhole => "PINHOLE",
            Self::Opencv => "OPENCV",
            Self::OpencvFisheye => "OPENCV_FISHEYE",
        }
    }
}

/// The path of the `views` cameras in front of the pane wall; every 8th view is a test view.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CameraPath {
    /// A closed loop 2.3 to 2.9 m from the wall, up to about 52 degrees off the pane normal,
    /// between 0.9 and 1.7 m high, looking at a point 0.8 m behind the glass.
    #[default]
    Loop,
    /// A level arc 2.7 m from the pane centre, from 45 degrees left to 45 degrees right, at
    /// 1.4 m: a capture that circles the glass and never turns round.
    Arc,
    /// A straight walk past the wall, 2.2 m from it, from x = -2.2 to 2.2 m, looking ahead and
    /// a little towards the pane: the pane is seen at a sweep of angles, often obliquely.
    WalkBy,
    /// Close-ups 1.6 to 1.9 m from the pane, within 30 degrees of its normal: the pane fills
    /// most of each view.
    CloseUp,
}

/// The room behind the glass in the default scene: a shop window seen from a brighter room,
/// which keeps the reflection (R0 = 0.2) clearly visible over the transmitted view.
pub const DAY_BEHIND_GAIN: f64 = 0.55;

/// The room behind the glass in the night variant: dimmer, so that the reflection carries a
/// larger share of each glass pixel, as a lit room's window at dusk.
pub const NIGHT_BEHIND_GAIN: f64 = 0.3;

impl Default for SyntheticConfig {
    fn default() -> Self {
        Self {
            width: 256,
            height: 192,
            views: 40,
            room_views: 8,
            seed: 7,
            panes: vec![PaneKind::Glass],
            masked_views: 6,
            sparse_points: 4000,
            behind_gain: DAY_BEHIND_GAIN,
            backdrop: Backdrop::Room,
            r0: None,
            pane_scale: 1.0,
            pane_turn_deg: Vec::new(),
            reflected_lights: 0,
            path: CameraPath::Loop,
            lens: SyntheticLens::Pinhole,
            setting: Setting::Room,
        }
    }
}

impl SyntheticConfig {
    /// A fast variant for tests: 64x48, 12 loop views and 2 room views, 800 points.
    pub fn small() -> Self {
        Self {
            width: 64,
            height: 48,
            views: 12,
            room_views: 2,
            masked_views: 3,
            sparse_points: 800,
            ..Self::default()
        }
    }

    /// The same room with no panes: the wall is then closed (no window openings, no frames), the
    /// images equal the transmission, and there are no masks and no planes.
    pub fn without_glass(self) -> Self {
        Self { panes: Vec::new(), ..self }
    }

    /// The same scene with the room behind the glass lit at [`NIGHT_BEHIND_GAIN`]: every view
    /// outside the panes is unchanged, and the reflection is a larger share of the glass pixels.
    pub fn night(self) -> Self {
        Self { behind_gain: NIGHT_BEHIND_GAIN, ..self }
    }

    /// The street fixture: four shop windows of glass and a mirror along a 24 m shop front,
    /// 240 views along two walks past it (every 8th a test view), 30 of them masked, 12000
    /// sparse points. Across the street stand facades that the glass reflects and no camera
    /// faces.
    pub fn street() -> Self {
        use PaneKind::{Glass, Mirror};
        Self {
            views: 240,
            room_views: 0,
            panes: vec![Glass, Glass, Glass, Mirror, Glass],
            masked_views: 30,
            sparse_points: 12_000,
            setting: Setting::Street,
            ..Self::default()
        }
    }

    /// The same camera room and cameras with [`Backdrop::Showcase`] behind the wall.
    pub fn showcase(self) -> Self {
        Self { backdrop: Backdrop::Showcase, ..self }
    }
}
