//! `train` without `--data` writes the built-in scene into `<out>/dataset` once (a marker file,
//! written last, names which one it is); asking for another `--demo-scene` in the same `--out` is
//! refused with the folder and both scene names, instead of silently training the scene already
//! there. Markers written before the showcase became the default name the window scene `glass`.
use std::process::Command;
use trgs_core::scratch::ScratchDir;

/// `train --out <scratch> --iterations 1 <extra>` on a dataset folder that holds only `marker`:
/// its stderr, after checking that it failed and named the folder.
fn refused_with_marker(name: &str, marker: &str, extra: &[&str]) -> String {
    let out = ScratchDir::new(name);
    let dataset = out.join("dataset");
    std::fs::create_dir_all(&dataset).expect("mkdir");
    // A written scene, as far as the check looks: the marker it ends with.
    std::fs::write(dataset.join("demo_scene.txt"), marker).expect("write");
    let refused = Command::new(env!("CARGO_BIN_EXE_train"))
        .arg("--out")
        .arg(&*out)
        .args(["--iterations", "1"])
        .args(extra)
        .output()
        .expect("run train");
    let stderr = String::from_utf8_lossy(&refused.stderr).into_owned();
    assert!(!refused.status.success(), "accepted: {stderr}");
    assert!(stderr.contains(&dataset.display().to_string()), "{stderr}");
    stderr
}

#[test]
fn another_demo_scene_in_the_same_out_folder_is_refused() {
    let stderr =
        refused_with_marker("demo-scene-cli", "window\n", &["--demo-scene", "night-window"]);
    assert!(
        stderr.contains("holds the built-in scene `--demo-scene window`, not `night-window`"),
        "{stderr}"
    );
}

#[test]
fn the_default_is_the_showcase_and_old_markers_name_the_window_scene() {
    let stderr = refused_with_marker("demo-scene-cli-old", "glass\n", &[]);
    assert!(
        stderr.contains("holds the built-in scene `--demo-scene window`, not `showcase`"),
        "{stderr}"
    );
}

#[test]
fn an_unknown_marker_is_an_error_that_names_it() {
    let stderr = refused_with_marker("demo-scene-cli-bad", "attic\n", &[]);
    assert!(stderr.contains("demo_scene.txt") && stderr.contains("\"attic\""), "{stderr}");
}
