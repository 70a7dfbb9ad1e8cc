//! `prepare` on photos the project makes: the built-in scene's views (every second of its orbit)
//! become a scene folder that trgs opens, with most views registered; photos that share nothing
//! and a missing COLMAP are named errors. Needs COLMAP's `colmap` program
//! (scripts/ensure-colmap.sh installs it, as scripts/test.sh does).
use std::path::Path;
use std::process::{Command, Output};
use trgs_core::io::SceneFolder;
use trgs_core::scratch::ScratchDir;
use trgs_train::RunConfig;

fn prepare(input: &Path, out: &Path, extra: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_trgs"))
        .arg("prepare")
        .arg(input)
        .arg("--out")
        .arg(out)
        .args(extra)
        .output()
        .expect("run prepare")
}

fn text(output: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    )
}

#[test]
fn the_built_in_scenes_photos_become_a_scene_folder() {
    assert!(
        Command::new("colmap").arg("help").output().is_ok(),
        "COLMAP's colmap program is missing: scripts/ensure-colmap.sh installs it"
    );
    let dir = ScratchDir::new("prepare-cli");
    let demo = RunConfig::default().demo_config();
    trgs_synthetic::write_generated(&demo, &dir.join("demo")).expect("the built-in scene");
    let photos = dir.join("demo").join("images");
    let scene = dir.join("scene");
    let made = prepare(&photos, &scene, &["--every", "2"]);
    let said = text(&made);
    assert!(made.status.success(), "{said}");
    let given = std::fs::read_dir(&photos).expect("photos").count().div_ceil(2);
    for stage in ["feature extraction done", "exhaustive matching done", "mapping done"] {
        assert!(said.contains(stage), "a line for each COLMAP stage: {said}");
    }
    let folder = SceneFolder::open(&scene).expect("trgs opens the scene folder");
    assert!(
        10 * folder.views.len() >= 7 * given,
        "{} of {given} views registered: {said}",
        folder.views.len()
    );
    assert!(folder.points.len() > 100, "{} sparse points", folder.points.len());
    assert!(said.contains(&format!("of {given} images registered")), "{said}");
    // A second prepare into the same folder is refused rather than mixed with the first.
    let again = prepare(&photos, &scene, &[]);
    let said = text(&again);
    assert!(!again.status.success() && said.contains("already a scene folder"), "{said}");
    // So is a folder of someone else's images/, and photos where prepare writes.
    let foreign = dir.join("foreign");
    std::fs::create_dir_all(foreign.join("images")).expect("folder");
    let refused = prepare(&photos, &foreign, &[]);
    assert!(text(&refused).contains("that prepare did not write"), "{}", text(&refused));
    let inside = prepare(&photos, &dir.join("demo"), &[]);
    assert!(text(&inside).contains("which prepare writes"), "{}", text(&inside));
}

#[test]
fn photos_that_share_nothing_and_a_missing_colmap_are_named() {
    let dir = ScratchDir::new("prepare-cli-errors");
    let photos = dir.join("noise");
    std::fs::create_dir_all(&photos).expect("folder");
    let mut state = 12345u32;
    for i in 0..3 {
        let img = image::RgbImage::from_fn(160, 120, |_, _| {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            image::Rgb([(state >> 24) as u8, (state >> 16) as u8, (state >> 8) as u8])
        });
        img.save(photos.join(format!("{i}.png"))).expect("noise photo");
    }
    let missing = prepare(&photos, &dir.join("a"), &["--colmap", "no-such-colmap"]);
    assert!(!missing.status.success());
    assert!(text(&missing).contains("COLMAP is not installed"), "{}", text(&missing));
    // COLMAP would map with FOV, which `train` then cannot read: refused before COLMAP runs.
    let fov = prepare(&photos, &dir.join("c"), &["--camera-model", "FOV"]);
    assert!(!fov.status.success());
    assert!(text(&fov).contains("FOV") && text(&fov).contains("SIMPLE_RADIAL"), "{}", text(&fov));
    assert!(!dir.join("c").exists(), "nothing written");
    let refused = prepare(&photos, &dir.join("b"), &[]);
    assert!(!refused.status.success());
    let said = text(&refused);
    assert!(
        said.contains("registered none of the 3 images") || said.contains("registered only"),
        "{said}"
    );
}

/// Write `script` to `path` as an executable (a stand-in for `colmap`).
#[cfg(unix)]
fn write_executable(path: &Path, script: &str) {
    use std::os::unix::fs::PermissionsExt;
    std::fs::write(path, script).expect("wrapper");
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755)).expect("chmod");
}

/// A `colmap` wrapper at `dir/colmap-logged` that appends each command it runs (not the help
/// queries) to `dir/calls`, and whose mapper fails while `dir/fail-mapping` exists.
#[cfg(unix)]
fn logged_colmap(dir: &Path) -> String {
    let wrapper = dir.join("colmap-logged");
    let (calls, fail) = (dir.join("calls"), dir.join("fail-mapping"));
    let script = format!(
        "#!/bin/sh\n\
         if [ \"$2\" != -h ]; then echo \"$1\" >> '{}'; fi\n\
         if [ \"$1\" = mapper ] && [ \"$2\" != -h ] && [ -e '{}' ]; then\n\
         \x20 echo 'No good initial image pair found.'; exit 1\n\
         fi\n\
         exec colmap \"$@\"\n",
        calls.display(),
        fail.display()
    );
    write_executable(&wrapper, &script);
    wrapper.to_str().expect("a UTF-8 scratch path").to_string()
}

/// A prepare whose mapping failed is run again into the same folder with another --matching:
/// the photos and features of the first run are kept, only the matching and mapping run again.
#[cfg(unix)]
#[test]
fn a_failed_prepare_is_resumed_without_extracting_features_again() {
    let dir = ScratchDir::new("prepare-cli-resume");
    let demo = RunConfig::default().demo_config();
    trgs_synthetic::write_generated(&demo, &dir.join("demo")).expect("the built-in scene");
    let colmap = logged_colmap(&dir);
    let (photos, scene) = (dir.join("demo").join("images"), dir.join("scene"));
    std::fs::write(dir.join("fail-mapping"), b"").expect("flag");
    let failed = prepare(&photos, &scene, &["--every", "2", "--colmap", &colmap]);
    let said = text(&failed);
    assert!(!failed.status.success(), "{said}");
    assert!(said.contains("a rerun into the same --out keeps the photos and features"), "{said}");
    assert!(scene.join("colmap").join("mapper.log").is_file(), "COLMAP's output is kept");
    std::fs::remove_file(dir.join("fail-mapping")).expect("flag");
    let args = ["--every", "2", "--colmap", &colmap, "--matching", "sequential"];
    let resumed = prepare(&photos, &scene, &args);
    let said = text(&resumed);
    assert!(resumed.status.success(), "{said}");
    assert!(said.contains("resuming the unfinished prepare"), "{said}");
    assert!(said.contains("photos: written by the earlier run"), "{said}");
    assert!(said.contains("feature extraction done by the earlier run"), "{said}");
    assert!(said.contains("sequential matching done ("), "{said}");
    let calls = std::fs::read_to_string(dir.join("calls")).expect("calls");
    let count = |c: &str| calls.lines().filter(|l| *l == c).count();
    assert_eq!(count("feature_extractor"), 1, "{calls}");
    assert_eq!((count("exhaustive_matcher"), count("sequential_matcher")), (1, 1), "{calls}");
    SceneFolder::open(&scene).expect("trgs opens the scene folder");
}

/// A capture whose mapping can only start from a pair seen at 2° or less (a video that only
/// pans, where COLMAP's RANSAC may miss the 4° pair it found in another run): `prepare` steps the
/// initial pair's angle down until a model registers. A wrapper around `colmap` plays the
/// mapper that finds no initial pair above 2°.
#[cfg(unix)]
#[test]
fn a_mapping_that_starts_only_from_a_small_angle_is_found() {
    let dir = ScratchDir::new("prepare-cli-small-angle");
    let demo = RunConfig::default().demo_config();
    trgs_synthetic::write_generated(&demo, &dir.join("demo")).expect("the built-in scene");
    let wrapper = dir.join("colmap-pans");
    write_executable(
        &wrapper,
        "#!/bin/sh\n\
         if [ \"$1\" = mapper ] && [ \"$2\" != -h ]; then\n\
         \x20 case \" $* \" in\n\
         \x20   *' --Mapper.init_min_tri_angle 2 '*|*' --Mapper.init_min_tri_angle 1 '*) ;;\n\
         \x20   *) echo 'No good initial image pair found.'; exit 1 ;;\n\
         \x20 esac\n\
         fi\n\
         exec colmap \"$@\"\n",
    );
    let scene = dir.join("scene");
    let photos = dir.join("demo").join("images");
    let wrapper = wrapper.to_str().expect("a UTF-8 scratch path");
    let made = prepare(&photos, &scene, &["--every", "2", "--colmap", wrapper]);
    let said = text(&made);
    assert!(made.status.success(), "{said}");
    for angle in ["4°", "2°"] {
        assert!(said.contains(&format!("mapping again from a pair seen at {angle}")), "{said}");
    }
    assert!(!said.contains("seen at 1°"), "stops at the first angle that maps: {said}");
    SceneFolder::open(&scene).expect("trgs opens the scene folder");
}
