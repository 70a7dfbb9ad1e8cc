//! `train` without `--data` writes the built-in scene into `<out>/dataset` once (a marker file,
//! written last, names which one it is); asking for another `--demo-scene` in the same `--out` is refused with the folder
//! and both scene names, instead of silently training the scene already there.
use std::process::Command;
use trgs_core::scratch::ScratchDir;

#[test]
fn another_demo_scene_in_the_same_out_folder_is_refused() {
    let out = ScratchDir::new("demo-scene-cli");
    let dataset = out.join("dataset");
    std::fs::create_dir_all(&dataset).expect("mkdir");
    // A written default scene, as far as the check looks: the marker it ends with.
    std::fs::write(dataset.join("demo_scene.txt"), "glass\n").expect("write");
    let refused = Command::new(env!("CARGO_BIN_EXE_train"))
        .arg("--out")
        .arg(&*out)
        .args(["--demo-scene", "night-glass", "--iterations", "1"])
        .output()
        .expect("run train");
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success(), "accepted: {stderr}");
    assert!(
        stderr.contains("holds the built-in scene `--demo-scene glass`, not `night-glass`"),
        "{stderr}"
    );
    assert!(stderr.contains(&dataset.display().to_string()), "{stderr}");
}
