//! Unit tests of `run::config`: the defaults, the flags' checks and the upgrade of older records.
use super::*;

fn config(densify: DensifyMode) -> RunConfig {
    RunConfig { densify, ..RunConfig::default() }
}

#[test]
fn defaults_are_the_help_texts() {
    let c = RunConfig::default();
    assert_eq!((c.iterations, c.sh_degree, c.random_init), (1000, 3, 10_000));
    let mut capture = RunConfig { data: Some("scene".into()), ..c.clone() };
    capture.default_iterations_unless(false);
    assert_eq!(capture.iterations, CAPTURE_ITERATIONS);
    let mut given = RunConfig { data: Some("scene".into()), iterations: 2000, ..c.clone() };
    given.default_iterations_unless(true);
    assert_eq!(given.iterations, 2000);
    assert_eq!((c.demo_scene, c.densify), (DemoScene::Showcase, DensifyMode::Classic));
    assert_eq!(c.out, PathBuf::from("runs/demo"));
    assert_eq!(c.resolution(), Resolution::LongSide(crate::data::DEFAULT_LONG_SIDE));
    c.check().expect("the defaults are consistent");
}

#[test]
fn demo_flags_shape_the_built_in_scene_and_name_it() {
    let c = RunConfig {
        demo_size: Some((1600, 1200)),
        demo_views: Some(200),
        demo_camera: DemoCamera::OpencvFisheye,
        ..RunConfig::default()
    };
    let s = c.demo_config();
    assert_eq!((s.width, s.height, s.views), (1600, 1200, 200));
    assert_eq!(s.lens, SyntheticLens::OpencvFisheye);
    assert_eq!(
        c.demo_flags(),
        "showcase --demo-size 1600x1200 --demo-views 200 --demo-camera opencv-fisheye"
    );
    assert_eq!(RunConfig::default().demo_flags(), "showcase", "old markers still match");
}

#[test]
fn a_library_caller_gets_the_command_line_refusals() {
    let bad: [(&str, RunConfig); 15] = [
        ("--iterations", RunConfig { iterations: 0, ..RunConfig::default() }),
        ("--sh-degree", RunConfig { sh_degree: 4, ..RunConfig::default() }),
        ("--eval-every", RunConfig { eval_every: Some(0), ..RunConfig::default() }),
        ("--downscale", RunConfig { downscale: Some(-1.0), ..RunConfig::default() }),
        (
            "one of --resolution and --downscale",
            RunConfig { resolution: Some(64), downscale: Some(2.0), ..RunConfig::default() },
        ),
        ("--cap", RunConfig { cap: Some(10), ..RunConfig::default() }),
        (
            "--grow-fraction shares",
            RunConfig {
                densify: DensifyMode::Mcmc,
                grow_fraction: Some(0.5),
                ..RunConfig::default()
            },
        ),
        ("--grow-fraction must", RunConfig { grow_fraction: Some(1.5), ..RunConfig::default() }),
        (
            "--prune-scale is part",
            RunConfig {
                densify: DensifyMode::Mcmc,
                prune_scale: Some(0.1),
                ..RunConfig::default()
            },
        ),
        ("--prune-scale must", RunConfig { prune_scale: Some(-0.1), ..RunConfig::default() }),
        (
            "--opacity-reset-every is part",
            RunConfig {
                densify: DensifyMode::Mcmc,
                opacity_reset_every: Some(0),
                ..RunConfig::default()
            },
        ),
        ("--cap 0", RunConfig { densify: DensifyMode::Mcmc, cap: Some(0), ..RunConfig::default() }),
        (
            "--full-size keeps",
            RunConfig { full_size: true, downscale: Some(2.0), ..RunConfig::default() },
        ),
        (
            "drop them with --data",
            RunConfig {
                data: Some(PathBuf::from("scene")),
                demo_camera: DemoCamera::Opencv,
                ..RunConfig::default()
            },
        ),
        ("--demo-size 8x600", RunConfig { demo_size: Some((8, 600)), ..RunConfig::default() }),
    ];
    for (words, config) in bad {
        let err = config.check().expect_err(words).to_string();
        assert!(err.contains(words), "{words}: {err}");
    }
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
fn old_checkpoints_resume_with_their_own_settings() {
    let record = |edit: &dyn Fn(&mut serde_json::Map<String, serde_json::Value>)| {
        let mut v = serde_json::to_value(RunConfig::default()).expect("config");
        let fields = v.as_object_mut().expect("an object");
        fields.remove("demo_scene");
        fields.remove("downscale");
        // The oldest records have only the first flag, and every record a cap.
        fields.insert("demo_no_glass".into(), false.into());
        fields.insert("resolution".into(), "Original".into());
        fields.insert("cap".into(), 300_000.into());
        edit(fields);
        upgrade_config_record(&mut v);
        serde_json::from_value::<RunConfig>(v).expect("readable")
    };
    assert_eq!(record(&|_| {}).demo_scene, DemoScene::Window);
    assert_eq!(record(&|_| {}).cap, None, "a classic run's cap meant nothing");
    let night = record(&|f| {
        f.insert("demo_night".into(), true.into());
    });
    assert_eq!(night.demo_scene, DemoScene::NightWindow);
    let showcase = record(&|f| {
        f.insert("demo_showcase".into(), true.into());
        f.insert("resolution".into(), serde_json::json!({"Width": 128}));
    });
    assert_eq!(showcase.demo_scene, DemoScene::Showcase);
    assert_eq!(showcase.resolution(), Resolution::Width(128));
    let mcmc = record(&|f| {
        f.insert("demo_no_glass".into(), true.into());
        f.insert("densify".into(), "Mcmc".into());
        f.insert("resolution".into(), serde_json::json!({"Downscale": 2.0}));
    });
    assert_eq!((mcmc.demo_scene, mcmc.cap), (DemoScene::NoGlass, Some(300_000)));
    assert_eq!(mcmc.resolution(), Resolution::Downscale(2.0));
    // A current record is left as it is.
    let mut current = serde_json::to_value(config(DensifyMode::Mcmc)).expect("config");
    upgrade_config_record(&mut current);
    let current: RunConfig = serde_json::from_value(current).expect("readable");
    assert_eq!(current, config(DensifyMode::Mcmc));
}

#[test]
fn mcmc_trains_opacities_at_its_own_rate() {
    assert_eq!(config(DensifyMode::Classic).settings().rates.opacity, 0.025);
    assert_eq!(config(DensifyMode::Mcmc).settings().rates.opacity, 0.05);
}

#[test]
fn the_opacity_reset_interval_replaces_the_scaled_one() {
    let resets = |c: &RunConfig| match c.densification() {
        Densification::Classic(s) => (1..=c.iterations).filter(|&t| s.resets_opacity_at(t)).count(),
        other => panic!("classic expected, got {other:?}"),
    };
    let scaled = RunConfig { iterations: 30_000, ..RunConfig::default() };
    assert_eq!(resets(&scaled), 4, "3000, 6000, 9000 and 12000");
    let never = RunConfig { opacity_reset_every: Some(0), ..scaled.clone() };
    assert_eq!(resets(&never), 0);
    let often = RunConfig { opacity_reset_every: Some(1000), ..scaled };
    assert_eq!(resets(&often), 14, "1000 ... 14000, while densification goes on");
}

#[test]
fn the_world_size_prune_is_off_unless_given_a_share() {
    let scale = |c: RunConfig| match c.densification() {
        Densification::Classic(s) => s.prune_scale,
        other => panic!("classic expected, got {other:?}"),
    };
    assert_eq!(scale(RunConfig::default()), f64::INFINITY, "none by default");
    assert_eq!(scale(RunConfig { prune_scale: Some(0.1), ..RunConfig::default() }), 0.1);
    assert_eq!(scale(RunConfig { prune_scale: Some(0.3), ..RunConfig::default() }), 0.3);
    assert_eq!(scale(RunConfig { prune_scale: Some(0.0), ..RunConfig::default() }), f64::INFINITY);
}
