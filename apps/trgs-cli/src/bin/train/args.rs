//! The `train` command line: its help text, its arguments (kept in checkpoints, so that
//! `--resume` continues with the run's own settings) and the training settings they select.
use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use trgs_core::synthetic::SyntheticConfig;
use trgs_train::data::Resolution;
use trgs_train::settings::TrainSettings;

pub const HELP: &str = "\
trgs train: TR-Gaussians training

USAGE:
    train [--data DIR] [--out DIR] [OPTIONS]
    train --out DIR --resume

OPTIONS:
    --data DIR          scene folder: COLMAP (sparse/0 + images/) or transforms.json, with
                        optional glass_masks/, planes.json and test_views.txt. Default: the
                        built-in synthetic scene, written to <out>/dataset
    --demo-scene KIND   the built-in scene: showcase (default: a shop window, a pane that
                        fills much of the view with a display just behind it), window (a
                        smaller window onto a second room), night-window (that room lit
                        dimmer, so the reflection is a larger share of the pane) or no-glass
    --out DIR           output folder (default: runs/demo)
    --iterations N      training steps (default 1000: about 3 minutes for the demo scene on a
                        2-core lavapipe; the paper uses 30000)
    --resolution W      train at width W (the height keeps the aspect ratio)
    --downscale F       train at 1/F of the image size
    --sh-degree D       largest SH degree, 0 to 3 (default 3)
    --eval-every N      evaluate the test views every N steps (default: 10 times a run)
    --checkpoint-every N  write <out>/checkpoint.trgs every N steps (default: at each evaluation)
    --resume            continue the run in --out from its checkpoint, with its own settings
    --random-init N     start from N random points when the scene has no sparse points
                        (default 10000)
    --no-planes         ignore the glass masks: plain 3DGS (the baseline of the comparisons)
    --densify MODE      classic (3DGS clone, split, prune, opacity reset; default), mcmc
                        (3DGS-MCMC: relocation of dead Gaussians, growth to --cap, noise,
                        opacity and scale regularisers) or none
    --cap N             mcmc: the most Gaussians (default 300000)
    --seed S            order of the training views (default 0)
    --profile           time every GPU stage of every step (timestamp queries) into log.jsonl
    --viewer            show training live in the viewer window (also with --resume); closing
                        the window lets training go on

ABLATIONS (the paper's table; each switches one component off):
    --no-multi-stage    no stage 2: joint optimisation right after stage 1
    --no-depth-loss     no depth variance loss L_d
    --no-conflict-loss  no gradient conflict loss L_c
    --no-perturbation   no opacity perturbation
    --no-intensity      no reflection intensity map: C_r = C_raw
    --no-fresnel        no Schlick: a constant learnable R = R0
    -h, --help          this text
";

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Args {
    pub data: Option<PathBuf>,
    /// The built-in scene trained on without `--data`.
    pub demo_scene: DemoScene,
    pub out: PathBuf,
    pub iterations: u32,
    pub resolution: Resolution,
    pub sh_degree: u32,
    pub eval_every: Option<u32>,
    pub checkpoint_every: Option<u32>,
    pub random_init: usize,
    pub densify: DensifyMode,
    /// MCMC's cap on the Gaussian count.
    pub cap: usize,
    pub no_planes: bool,
    pub seed: u64,
    pub profile: bool,
    pub ablations: Ablations,
}

/// The built-in synthetic scenes (`--demo-scene`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum DemoScene {
    /// A shop window: a 2.4 m x 1.4 m pane, 41% of the test pixels, with a display 0.15-1.45 m
    /// behind it (the case of the paper's largest gains).
    Showcase,
    /// A 1.6 m x 1.0 m pane onto a second room 4.5 m deep (18% of the test pixels).
    Window,
    /// The window scene with the room behind the glass lit dimmer.
    NightWindow,
    /// The window scene's room with the wall closed: no glass, no masks.
    NoGlass,
}

impl DemoScene {
    pub const ALL: [DemoScene; 4] =
        [Self::Showcase, Self::Window, Self::NightWindow, Self::NoGlass];

    /// The `--demo-scene` value, also written in the dataset's marker file.
    pub fn name(self) -> &'static str {
        match self {
            Self::Showcase => "showcase",
            Self::Window => "window",
            Self::NightWindow => "night-window",
            Self::NoGlass => "no-glass",
        }
    }

    /// The scene named `name`; `glass` and `night-glass` are the window scenes' names before
    /// the showcase became the default, still found in older datasets' marker files.
    pub fn parse(name: &str) -> Option<Self> {
        match name {
            "glass" => Some(Self::Window),
            "night-glass" => Some(Self::NightWindow),
            _ => Self::ALL.into_iter().find(|s| s.name() == name),
        }
    }

    pub fn description(self) -> &'static str {
        match self {
            Self::Showcase => "showcase scene",
            Self::Window => "window scene",
            Self::NightWindow => "window scene at night",
            Self::NoGlass => "scene without glass",
        }
    }

    pub fn config(self) -> SyntheticConfig {
        let window = SyntheticConfig::default();
        match self {
            Self::Showcase => window.showcase(),
            Self::Window => window,
            Self::NightWindow => window.night(),
            Self::NoGlass => window.without_glass(),
        }
    }
}

/// Checkpoints written before [`DemoScene`] named the built-in scene by three flags (all false
/// for the window scene, then the default). Rewrites such a record of [`Args`] in place so that
/// `--resume` continues those runs on their own scene.
pub fn upgrade_args_record(args: &mut serde_json::Value) {
    let Some(fields) = args.as_object_mut() else { return };
    if fields.contains_key("demo_scene") {
        return;
    }
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
    fields.insert("demo_scene".into(), serde_json::to_value(scene).expect("a unit variant"));
}

/// How the Gaussian count changes during training.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum DensifyMode {
    Classic,
    Mcmc,
    None,
}

/// The paper's ablations: each true switches one component off.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Ablations {
    pub no_multi_stage: bool,
    pub no_depth_loss: bool,
    pub no_conflict_loss: bool,
    pub no_perturbation: bool,
    pub no_intensity: bool,
    pub no_fresnel: bool,
}

impl Ablations {
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

/// What the command line asked for.
pub enum Command {
    Help,
    Train(Args),
    Resume { out: PathBuf },
}

/// The settings of a run without flags (the help text's defaults).
impl Default for Args {
    fn default() -> Self {
        Self {
            data: None,
            demo_scene: DemoScene::Showcase,
            out: PathBuf::from("runs/demo"),
            iterations: 1000,
            resolution: Resolution::Original,
            sh_degree: 3,
            eval_every: None,
            checkpoint_every: None,
            random_init: 10_000,
            densify: DensifyMode::Classic,
            cap: 300_000,
            no_planes: false,
            seed: 0,
            profile: false,
            ablations: Ablations::default(),
        }
    }
}

/// The command, and whether to show training in the viewer (not a setting of the run: a resumed
/// run may be watched or not).
pub fn parse_args() -> Result<(Command, bool)> {
    let mut args = Args::default();
    let mut resume = false;
    let mut viewer = false;
    // Flags that only mean something with another: refused alone rather than ignored.
    let (mut resolution_flags, mut demo_scene, mut cap) = (0, false, false);
    let mut others = Vec::new();
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        let mut value = |name: &str| it.next().with_context(|| format!("{name} needs a value"));
        fn num<T: std::str::FromStr>(name: &str, v: String) -> Result<T> {
            v.parse().map_err(|_| anyhow::anyhow!("{name} {v:?}: expected a number"))
        }
        if !matches!(a.as_str(), "--out" | "--resume" | "--viewer") {
            others.push(a.clone());
        }
        let ab = &mut args.ablations;
        match a.as_str() {
            "-h" | "--help" => return Ok((Command::Help, false)),
            "--viewer" => viewer = true,
            "--data" => args.data = Some(PathBuf::from(value("--data")?)),
            "--demo-scene" => {
                demo_scene = true;
                let name = value("--demo-scene")?;
                args.demo_scene = DemoScene::parse(&name).with_context(|| {
                    let names: Vec<_> = DemoScene::ALL.iter().map(|s| s.name()).collect();
                    format!("--demo-scene {name:?}: expected {}", names.join(", "))
                })?;
            }
            "--out" => args.out = PathBuf::from(value("--out")?),
            "--resume" => resume = true,
            "--iterations" => args.iterations = num("--iterations", value("--iterations")?)?,
            "--resolution" => {
                resolution_flags += 1;
                args.resolution = Resolution::Width(num("--resolution", value("--resolution")?)?)
            }
            "--downscale" => {
                resolution_flags += 1;
                args.resolution = Resolution::Downscale(num("--downscale", value("--downscale")?)?)
            }
            "--sh-degree" => args.sh_degree = num("--sh-degree", value("--sh-degree")?)?,
            "--eval-every" => args.eval_every = Some(num("--eval-every", value("--eval-every")?)?),
            "--checkpoint-every" => {
                args.checkpoint_every =
                    Some(num("--checkpoint-every", value("--checkpoint-every")?)?)
            }
            "--random-init" => args.random_init = num("--random-init", value("--random-init")?)?,
            "--densify" => {
                args.densify = match value("--densify")?.as_str() {
                    "classic" => DensifyMode::Classic,
                    "mcmc" => DensifyMode::Mcmc,
                    "none" => DensifyMode::None,
                    other => bail!("--densify {other:?}: expected classic, mcmc or none"),
                }
            }
            "--cap" => {
                cap = true;
                args.cap = num("--cap", value("--cap")?)?
            }
            "--no-planes" => args.no_planes = true,
            "--profile" => args.profile = true,
            "--seed" => args.seed = num("--seed", value("--seed")?)?,
            "--no-multi-stage" => ab.no_multi_stage = true,
            "--no-depth-loss" => ab.no_depth_loss = true,
            "--no-conflict-loss" => ab.no_conflict_loss = true,
            "--no-perturbation" => ab.no_perturbation = true,
            "--no-intensity" => ab.no_intensity = true,
            "--no-fresnel" => ab.no_fresnel = true,
            other => bail!("unknown argument {other:?}\n\n{HELP}"),
        }
    }
    if resume {
        if !others.is_empty() {
            bail!(
                "--resume continues a run with the settings it started with; drop {}",
                others.join(" ")
            );
        }
        return Ok((Command::Resume { out: args.out }, viewer));
    }
    if args.iterations == 0 {
        bail!("--iterations must be at least 1");
    }
    if args.sh_degree > 3 {
        bail!("--sh-degree {}: expected 0 to 3", args.sh_degree);
    }
    if args.checkpoint_every == Some(0) || args.eval_every == Some(0) {
        bail!("--eval-every and --checkpoint-every must be at least 1");
    }
    if resolution_flags > 1 {
        bail!("give one of --resolution and --downscale");
    }
    if demo_scene && args.data.is_some() {
        bail!("--demo-scene chooses the built-in scene, which --data replaces: give one of them");
    }
    if cap && args.densify != DensifyMode::Mcmc {
        bail!("--cap is the MCMC count: it needs --densify mcmc");
    }
    if args.no_planes && !args.ablations.names().is_empty() {
        bail!(
            "--no-planes trains plain 3DGS, which has none of TR-Gaussians' components to switch \
             off: drop the ablation flags ({})",
            args.ablations.names().join(", ")
        );
    }
    Ok((Command::Train(args), viewer))
}

/// The training settings `args` ask for.
pub fn settings_of(args: &Args) -> TrainSettings {
    let mut s = TrainSettings::scaled(args.iterations);
    s.sh_degree = args.sh_degree;
    s.seed = args.seed;
    let ab = &args.ablations;
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
    if args.densify == DensifyMode::Mcmc {
        s.rates.opacity = trgs_train::densify::mcmc::OPACITY_LEARNING_RATE;
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(densify: DensifyMode) -> Args {
        Args { densify, ..Args::default() }
    }

    #[test]
    fn demo_scene_names_round_trip_and_old_names_still_parse() {
        for scene in DemoScene::ALL {
            assert_eq!(DemoScene::parse(scene.name()), Some(scene));
        }
        assert_eq!(DemoScene::parse("glass"), Some(DemoScene::Window));
        assert_eq!(DemoScene::parse("night-glass"), Some(DemoScene::NightWindow));
        assert_eq!(DemoScene::parse("attic"), None);
    }

    #[test]
    fn old_checkpoints_resume_on_their_own_demo_scene() {
        let record = |flags: &[&str]| {
            let mut v = serde_json::to_value(Args::default()).expect("args");
            let fields = v.as_object_mut().expect("an object");
            fields.remove("demo_scene");
            // The oldest records have only the first flag.
            fields.insert("demo_no_glass".into(), false.into());
            for f in flags {
                fields.insert((*f).into(), true.into());
            }
            upgrade_args_record(&mut v);
            serde_json::from_value::<Args>(v).expect("readable").demo_scene
        };
        assert_eq!(record(&[]), DemoScene::Window);
        assert_eq!(record(&["demo_night"]), DemoScene::NightWindow);
        assert_eq!(record(&["demo_showcase"]), DemoScene::Showcase);
        assert_eq!(record(&["demo_no_glass"]), DemoScene::NoGlass);
        let mut current = serde_json::to_value(Args::default()).expect("args");
        upgrade_args_record(&mut current);
        let current: Args = serde_json::from_value(current).expect("readable");
        assert_eq!(current.demo_scene, DemoScene::Showcase);
    }

    #[test]
    fn mcmc_trains_opacities_at_its_own_rate() {
        assert_eq!(settings_of(&args(DensifyMode::Classic)).rates.opacity, 0.025);
        assert_eq!(settings_of(&args(DensifyMode::Mcmc)).rates.opacity, 0.05);
    }
}
