//! The settings of a whole run: the `train` command's arguments (clap derives its parser and
//! help from this type) and the record a checkpoint keeps, so that `--resume` continues a run
//! with its own settings. Defaults live in the clap attributes only; [`RunConfig::default`]
//! parses an empty command line.
use super::arg_parsers::{
    parse_image_size, parse_non_negative, parse_positive, parse_positive_share,
};
use crate::data::Resolution;
use crate::densify::{ClassicSettings, Densification, McmcSettings};
use crate::exposure::ExposureRates;
use crate::settings::TrainSettings;
use anyhow::{Result, bail};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use trgs_synthetic::{SyntheticConfig, SyntheticLens};

/// MCMC's cap on the Gaussian count when `--cap` is not given.
pub const DEFAULT_MCMC_CAP: usize = 300_000;

/// Everything a training run is configured with.
#[derive(Clone, Debug, PartialEq, clap::Args, Serialize, Deserialize)]
pub struct RunConfig {
    /// Scene folder: COLMAP (sparse/0 + images/) or transforms.json, with optional
    /// glass_masks/, planes.json and test_views.txt [default: the built-in scene, written to
    /// the --out folder's dataset/]
    #[arg(long, value_name = "DIR", conflicts_with = "demo_scene")]
    pub data: Option<PathBuf>,
    /// The built-in synthetic scene trained on without --data
    #[arg(long, value_enum, value_name = "SCENE", default_value = "showcase")]
    pub demo_scene: DemoScene,
    /// The built-in scene's photo size, e.g. 1600x1200 [default: 256x192]
    #[arg(long, value_name = "WxH", value_parser = parse_image_size, conflicts_with = "data")]
    #[serde(default)]
    pub demo_size: Option<(u32, u32)>,
    /// Views on the built-in scene's camera loop, every 8th a test view (8 views looking back
    /// into the camera room come on top) [default: 40; the street's 240 along its walks]
    #[arg(long, value_name = "N", conflicts_with = "data",
          value_parser = clap::value_parser!(u32).range(2..))]
    #[serde(default)]
    pub demo_views: Option<u32>,
    /// The lens the built-in scene's photos are taken through (written as its COLMAP model;
    /// training undistorts them)
    #[arg(
        long,
        value_enum,
        value_name = "MODEL",
        default_value = "pinhole",
        conflicts_with = "data"
    )]
    #[serde(default)]
    pub demo_camera: DemoCamera,
    /// Output folder
    #[arg(long, value_name = "DIR", default_value = "runs/demo")]
    pub out: PathBuf,
    /// Training steps [default: 1000 on the built-in scene (about 3 minutes on a 2-core
    /// lavapipe), 30000 with --data]. A real capture needs the paper's 30000 (as the INRIA code,
    /// gsplat and Brush train): the demo's 1000 are too few for one. Every schedule scales with it
    #[arg(long, value_name = "N", default_value_t = DEMO_ITERATIONS, hide_default_value = true,
          value_parser = clap::value_parser!(u32).range(1..))]
    pub iterations: u32,
    /// Train at width W (the height keeps the aspect ratio) [default: the images' size, up to
    /// 1600 px on the longer side]
    #[arg(long, value_name = "W", conflicts_with = "downscale",
          value_parser = clap::value_parser!(u32).range(1..))]
    #[serde(default)]
    pub resolution: Option<u32>,
    /// Train at 1/F of the image size
    #[arg(long, value_name = "F", value_parser = parse_positive)]
    #[serde(default)]
    pub downscale: Option<f64>,
    /// Train at the photos' own size, however large (by default a photo whose longer side
    /// exceeds 1600 px is trained at 1600)
    #[arg(long, conflicts_with_all = ["resolution", "downscale"])]
    #[serde(default)]
    pub full_size: bool,
    /// Largest SH degree
    #[arg(long, value_name = "D", default_value_t = 3,
          value_parser = clap::value_parser!(u32).range(0..=3))]
    pub sh_degree: u32,
    /// Evaluate the test views every N steps [default: ten times a run]
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub eval_every: Option<u32>,
    /// Write checkpoint.trgs into the --out folder every N steps [default: at each evaluation]
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub checkpoint_every: Option<u32>,
    /// Start from N random points when the scene has no sparse points
    #[arg(long, value_name = "N", default_value_t = 10_000)]
    pub random_init: usize,
    /// How the Gaussian count changes
    #[arg(long, value_enum, value_name = "MODE", default_value = "classic")]
    pub densify: DensifyMode,
    /// The most Gaussians of --densify mcmc [default: 300000]
    #[arg(long, value_name = "N")]
    pub cap: Option<usize>,
    /// Of the Gaussians over --densify classic's gradient threshold at each densification,
    /// densify only the share F (0 to 1) with the largest average gradients, as Brush grows a
    /// share of its candidates; on short videos (10-20 frames) 3DGS's rule overfits over the
    /// 30000-step schedule, and 0.25 held their test views level (docs/captures.md) [default:
    /// 1, all of them, as 3DGS]
    #[arg(long, value_name = "F", value_parser = parse_positive_share)]
    #[serde(default)]
    pub grow_fraction: Option<f64>,
    /// Cap every opacity at 0.01 each N steps while --densify classic grows, so that what
    /// the next densifications find transparent is pruned; --prune-scale's prune starts after
    /// the first (3DGS's reset; 0: no reset and no such prune, as Brush, which lowers
    /// opacities a little at each refinement instead) [default: 3000 of 30000 steps, scaled
    /// with --iterations, and none in runs of 2000 steps or fewer]
    #[arg(long, value_name = "N")]
    #[serde(default)]
    pub opacity_reset_every: Option<u32>,
    /// After the first opacity reset, prune Gaussians larger than F times the scene extent
    /// (the training cameras' radius) at each densification of --densify classic: 3DGS's rule
    /// is 0.1 [default: 0, never, as Brush: a capture's background lies far beyond its cameras]
    #[arg(long, value_name = "F", value_parser = parse_non_negative)]
    #[serde(default)]
    pub prune_scale: Option<f64>,
    /// Ignore the glass masks: plain 3DGS (the baseline of the comparisons); the same as
    /// `--planes none`
    #[arg(long)]
    pub no_planes: bool,
    /// Where the reflection planes come from: `masks` fits them to glass_masks/ (the paper's
    /// annotation), `auto` proposes them from the scene after stage 1 and keeps those that
    /// pay (masks ignored), `none` trains plain 3DGS [default: masks when the scene folder has
    /// glass_masks/, none otherwise]
    #[arg(long, value_enum, value_name = "SOURCE", conflicts_with = "no_planes")]
    #[serde(default)]
    pub planes: Option<PlaneSource>,
    /// Do not mirror what stage 1 learnt behind each plane to its front when the plane is
    /// initialised: the reflection layer then starts empty
    #[arg(long, conflicts_with = "no_planes")]
    #[serde(default)]
    pub no_reflection_seeds: bool,
    /// Keep each plane as fitted to the Gaussians around the mask outline (the paper's
    /// initialisation), without moving it onto the glass the masks outline
    #[arg(long, conflicts_with = "no_planes")]
    #[serde(default)]
    pub no_mask_refinement: bool,
    /// Per-view exposure compensation: learn an affine colour map per training photo (its
    /// exposure and white balance), which the loss applies to the render; the model stays one
    /// exposure. Test views' maps are fitted on the photo's left half and scored on its right
    /// (metrics.json's `right_half`)
    #[arg(long, value_enum, value_name = "ON|OFF", default_value = "off")]
    #[serde(default)]
    pub exposure: ExposureMode,
    /// GPU memory for the training views' photos, in MiB; beyond it views are streamed, each
    /// uploaded a step ahead of its use [default: 64 on a CPU adapter such as lavapipe, whose
    /// "GPU memory" is the RAM that already holds the photos; 4096 on a GPU]
    #[arg(long, value_name = "MIB")]
    #[serde(default)]
    pub target_memory: Option<u64>,
    /// Order of the training views and every random draw
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
    /// Time every GPU stage of every step (timestamp queries) into log.jsonl
    #[arg(long)]
    pub profile: bool,
    #[command(flatten)]
    pub ablations: Ablations,
}

/// The paper's ablations: each switches one component of TR-Gaussians off.
#[derive(Clone, Debug, Default, PartialEq, Eq, clap::Args, Serialize, Deserialize)]
#[command(next_help_heading = "Ablations (the paper's table; each switches one component off)")]
pub struct Ablations {
    /// No stage 2: joint optimisation right after stage 1
    #[arg(long, conflicts_with = "no_planes")]
    pub no_multi_stage: bool,
    /// No depth variance loss L_d
    #[arg(long, conflicts_with = "no_planes")]
    pub no_depth_loss: bool,
    /// No gradient conflict loss L_c
    #[arg(long, conflicts_with = "no_planes")]
    pub no_conflict_loss: bool,
    /// No opacity perturbation
    #[arg(long, conflicts_with = "no_planes")]
    pub no_perturbation: bool,
    /// No reflection intensity map: C_r = C_raw
    #[arg(long, conflicts_with = "no_planes")]
    pub no_intensity: bool,
    /// No Schlick: a constant learnable R = R0
    #[arg(long, conflicts_with = "no_planes")]
    pub no_fresnel: bool,
}

impl Ablations {
    /// The components switched off, by name.
    pub fn names(&self) -> Vec<&'static str> {
        [
            (self.no_multi_stage, "no multi-stage"),
            (self.no_depth_loss, "no L_d"),
            (self.no_conflict_loss, "no L_c"),
            (self.no_perturbation, "no opacity perturbation"),
            (self.no_intensity, "no reflection intensity"),
            (self.no_fresnel, "no Fresnel"),
        ]
        .into_iter()
        .filter_map(|(on, name)| on.then_some(name))
        .collect()
    }
}

/// The built-in synthetic scenes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
pub enum DemoScene {
    /// A shop window: a 2.4 m x 1.4 m pane, 41% of the test pixels, with a display just behind
    Showcase,
    /// A 1.6 m x 1.0 m pane onto a second room 4.5 m deep (18% of the test pixels)
    #[value(alias = "glass")]
    Window,
    /// The window scene with the room behind the glass lit dimmer
    #[value(alias = "night-glass")]
    NightWindow,
    /// The window scene's room with the wall closed: no glass, no masks
    NoGlass,
    /// A street of four shop windows and a mirror, 240 views along two walks past them: the
    /// scene for trgs split and merge
    Street,
}

impl DemoScene {
    pub const ALL: [DemoScene; 5] =
        [Self::Showcase, Self::Window, Self::NightWindow, Self::NoGlass, Self::Street];

    /// The `--demo-scene` value, also written in the dataset's marker file.
    pub fn name(self) -> &'static str {
        match self {
            Self::Showcase => "showcase",
            Self::Window => "window",
            Self::NightWindow => "night-window",
            Self::NoGlass => "no-glass",
            Self::Street => "street",
        }
    }

    /// The scene named `name`; `glass` and `night-glass` are the window scenes' names before
    /// the showcase became the default, still found in older datasets' marker files.
    pub fn parse(name: &str) -> Option<Self> {
        <Self as clap::ValueEnum>::from_str(name, false).ok()
    }

    pub fn description(self) -> &'static str {
        match self {
            Self::Showcase => "showcase scene",
            Self::Window => "window scene",
            Self::NightWindow => "window scene at night",
            Self::NoGlass => "scene without glass",
            Self::Street => "street scene",
        }
    }

    pub fn config(self) -> SyntheticConfig {
        let window = SyntheticConfig::default();
        match self {
            Self::Showcase => window.showcase(),
            Self::Window => window,
            Self::NightWindow => window.night(),
            Self::NoGlass => window.without_glass(),
            Self::Street => SyntheticConfig::street(),
        }
    }
}

/// Where a run's reflection planes come from (`--planes`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PlaneSource {
    /// Proposed from the scene after stage 1, each kept only if it pays
    Auto,
    /// Fitted to the glass masks after stage 1
    Masks,
    /// No planes: plain 3DGS
    None,
}

/// The lens of the built-in scene's photos (`--demo-camera`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
pub enum DemoCamera {
    /// PINHOLE: no distortion
    #[default]
    Pinhole,
    /// OPENCV: a phone camera's mild barrel distortion
    Opencv,
    /// OPENCV_FISHEYE: an action camera's fisheye
    OpencvFisheye,
}

impl DemoCamera {
    pub fn lens(self) -> SyntheticLens {
        match self {
            Self::Pinhole => SyntheticLens::Pinhole,
            Self::Opencv => SyntheticLens::Opencv,
            Self::OpencvFisheye => SyntheticLens::OpencvFisheye,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::Pinhole => "pinhole",
            Self::Opencv => "opencv",
            Self::OpencvFisheye => "opencv-fisheye",
        }
    }
}

impl RunConfig {
    /// The built-in scene this run trains on without --data: the scene with its size, view count
    /// and lens.
    pub fn demo_config(&self) -> SyntheticConfig {
        let mut c = self.demo_scene.config();
        if let Some((w, h)) = self.demo_size {
            (c.width, c.height) = (w, h);
        }
        if let Some(n) = self.demo_views {
            c.views = n as usize;
        }
        c.lens = self.demo_camera.lens();
        c
    }

    /// The flags that choose the built-in scene, as the dataset's marker file records them: the
    /// scene's name, then any of --demo-size, --demo-views and --demo-camera not at their
    /// defaults.
    pub fn demo_flags(&self) -> String {
        let mut s = self.demo_scene.name().to_string();
        if let Some((w, h)) = self.demo_size {
            s.push_str(&format!(" --demo-size {w}x{h}"));
        }
        if let Some(n) = self.demo_views {
            s.push_str(&format!(" --demo-views {n}"));
        }
        if self.demo_camera != DemoCamera::Pinhole {
            s.push_str(&format!(" --demo-camera {}", self.demo_camera.name()));
        }
        s
    }
}

/// `--iterations` on the built-in scene when not given.
pub const DEMO_ITERATIONS: u32 = 1000;

/// `--iterations` with `--data` when not given: the paper's, and what the INRIA code, gsplat and
/// Brush train a capture for.
pub const CAPTURE_ITERATIONS: u32 = 30_000;

/// Whether training learns a per-view exposure.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
pub enum ExposureMode {
    On,
    #[default]
    Off,
}

impl ExposureMode {
    pub fn is_on(self) -> bool {
        self == Self::On
    }
}

/// How the Gaussian count changes during training.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
pub enum DensifyMode {
    /// 3DGS: clone, split, prune, opacity reset
    Classic,
    /// 3DGS-MCMC: relocation of dead Gaussians, growth to --cap, noise, regularisers
    Mcmc,
    /// The count stays as initialised
    None,
}

/// The settings of a run without arguments (the defaults of the clap attributes).
impl Default for RunConfig {
    fn default() -> Self {
        #[derive(clap::Parser)]
        struct Defaults {
            #[command(flatten)]
            config: RunConfig,
        }
        #[allow(clippy::expect_used)]
        let parsed = <Defaults as clap::Parser>::try_parse_from(["train"])
            .expect("the defaults of RunConfig parse");
        parsed.config
    }
}

impl RunConfig {
    /// Refuse settings out of range or where one would be silently ignored (clap checks the
    /// ranges of the command line too; this is what a library caller gets).
    pub fn check(&self) -> Result<()> {
        if self.iterations == 0 {
            bail!("--iterations must be at least 1");
        }
        if self.sh_degree > 3 {
            bail!("--sh-degree {}: expected 0 to 3", self.sh_degree);
        }
        if self.eval_every == Some(0) || self.checkpoint_every == Some(0) {
            bail!("--eval-every and --checkpoint-every must be at least 1");
        }
        if self.resolution == Some(0) || self.downscale.is_some_and(|f| !(f > 0.0 && f.is_finite()))
        {
            bail!("--resolution must be at least 1 and --downscale above 0");
        }
        if self.resolution.is_some() && self.downscale.is_some() {
            bail!("give one of --resolution and --downscale");
        }
        if self.full_size && (self.resolution.is_some() || self.downscale.is_some()) {
            bail!("--full-size keeps the photos' size: drop --resolution and --downscale");
        }
        let demo_shaped = self.demo_size.is_some()
            || self.demo_views.is_some()
            || self.demo_camera != DemoCamera::Pinhole;
        if self.data.is_some() && demo_shaped {
            bail!(
                "--demo-size, --demo-views and --demo-camera shape the built-in scene: drop them with --data"
            );
        }
        if let Some((w, h)) = self.demo_size.filter(|&(w, h)| w < 16 || h < 16) {
            bail!("--demo-size {w}x{h}: each side must be at least 16");
        }
        if self.demo_views.is_some_and(|n| n < 2) {
            bail!("--demo-views must be at least 2");
        }
        if self.cap.is_some() && self.densify != DensifyMode::Mcmc {
            bail!("--cap is the MCMC count: it needs --densify mcmc");
        }
        if self.grow_fraction.is_some() && self.densify != DensifyMode::Classic {
            bail!("--grow-fraction shares out classic growth: it needs --densify classic");
        }
        if self.grow_fraction.is_some_and(|f| !(f > 0.0 && f <= 1.0)) {
            bail!("--grow-fraction must be above 0 and at most 1");
        }
        if self.prune_scale.is_some() && self.densify != DensifyMode::Classic {
            bail!("--prune-scale is part of classic densification: it needs --densify classic");
        }
        if self.prune_scale.is_some_and(|f| !(f.is_finite() && f >= 0.0)) {
            bail!("--prune-scale must be a number 0 or above");
        }
        if self.opacity_reset_every.is_some() && self.densify != DensifyMode::Classic {
            bail!(
                "--opacity-reset-every is part of classic densification: it needs --densify classic"
            );
        }
        if self.cap == Some(0) {
            bail!("--cap 0: MCMC keeps at most --cap Gaussians, so it must be at least 1");
        }
        let plain = self.no_planes || self.planes == Some(PlaneSource::None);
        if plain && !self.ablations.names().is_empty() {
            bail!(
                "--no-planes (--planes none) trains plain 3DGS, which has none of TR-Gaussians' \
                 components to switch off: drop the ablation flags ({})",
                self.ablations.names().join(", ")
            );
        }
        Ok(())
    }

    /// Unless `--iterations` was `given`, the default for what is trained: [`DEMO_ITERATIONS`]
    /// on the built-in scene (clap's default), [`CAPTURE_ITERATIONS`] with `--data`.
    pub fn default_iterations_unless(&mut self, given: bool) {
        if !given {
            self.iterations =
                if self.data.is_some() { CAPTURE_ITERATIONS } else { DEMO_ITERATIONS };
        }
    }

    /// Where the planes come from for a dataset with (`has_masks`) or without glass masks.
    pub fn plane_source(&self, has_masks: bool) -> PlaneSource {
        if self.no_planes {
            return PlaneSource::None;
        }
        self.planes.unwrap_or(if has_masks { PlaneSource::Masks } else { PlaneSource::None })
    }

    /// The training resolution.
    pub fn resolution(&self) -> Resolution {
        Resolution::from_flags(self.resolution, self.downscale, self.full_size)
    }

    /// The densification, with its schedule scaled to the run.
    pub fn densification(&self) -> Densification {
        match self.densify {
            DensifyMode::Classic => {
                let mut settings = ClassicSettings::scaled(self.iterations);
                settings.grow_fraction = self.grow_fraction.unwrap_or(1.0);
                if let Some(every) = self.opacity_reset_every {
                    settings.opacity_reset_every = every;
                }
                match self.prune_scale {
                    Some(f) if f > 0.0 => settings.prune_scale = f,
                    Some(_) => settings.prune_scale = f64::INFINITY,
                    None => {}
                }
                Densification::Classic(settings)
            }
            DensifyMode::Mcmc => Densification::Mcmc(McmcSettings::scaled(
                self.iterations,
                self.cap.unwrap_or(DEFAULT_MCMC_CAP),
            )),
            DensifyMode::None => Densification::None,
        }
    }

    /// The training settings these arguments select.
    pub fn settings(&self) -> TrainSettings {
        let mut s = TrainSettings::scaled(self.iterations);
        s.sh_degree = self.sh_degree;
        s.seed = self.seed;
        let ab = &self.ablations;
        if ab.no_multi_stage {
            s.stage2 = 0;
        }
        if ab.no_depth_loss {
            s.lambda_depth = 0.0;
        }
        if ab.no_conflict_loss {
            s.lambda_conflict = 0.0;
        }
        if ab.no_perturbation {
            s.perturb = None;
        }
        s.reflection.intensity = !ab.no_intensity;
        s.reflection.fresnel = !ab.no_fresnel;
        if self.densify == DensifyMode::Mcmc {
            s.rates.opacity = crate::densify::mcmc::OPACITY_LEARNING_RATE;
        }
        if self.exposure.is_on() {
            s.exposure = Some(ExposureRates::default());
        }
        s
    }
}

/// Rewrites a checkpoint's record of the settings written by an older version in place, so that
/// `--resume` continues those runs as they were configured:
/// - the built-in scene named by three flags (all false for the window scene, then the default)
///   instead of `demo_scene`;
/// - the resolution as one enum value instead of `resolution` (a width) and `downscale`;
/// - `cap` written for every densification, where it now means MCMC's cap only.
pub fn upgrade_config_record(record: &mut serde_json::Value) {
    let Some(fields) = record.as_object_mut() else { return };
    if !fields.contains_key("demo_scene") {
        let flag = |name: &str| fields.get(name).and_then(serde_json::Value::as_bool) == Some(true);
        let scene = if flag("demo_no_glass") {
            DemoScene::NoGlass
        } else if flag("demo_night") {
            DemoScene::NightWindow
        } else if flag("demo_showcase") {
            DemoScene::Showcase
        } else {
            DemoScene::Window
        };
        for old in ["demo_no_glass", "demo_night", "demo_showcase"] {
            fields.remove(old);
        }
        fields.insert("demo_scene".into(), serde_json::json!(scene));
    }
    let old_resolution = fields.get("resolution").cloned();
    if let Some(old) = old_resolution.filter(|v| !v.is_null() && !v.is_number()) {
        let (width, factor) = match &old {
            serde_json::Value::Object(o) => (o.get("Width").cloned(), o.get("Downscale").cloned()),
            _ => (None, None),
        };
        fields.insert("resolution".into(), width.unwrap_or(serde_json::Value::Null));
        fields.insert("downscale".into(), factor.unwrap_or(serde_json::Value::Null));
    }
    if fields.get("densify").and_then(serde_json::Value::as_str) != Some("Mcmc") {
        fields.insert("cap".into(), serde_json::Value::Null);
    }
}

#[cfg(test)]
#[path = "config_tests.rs"]
mod tests;
