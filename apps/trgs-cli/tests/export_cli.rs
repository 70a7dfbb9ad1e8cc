//! The `convert` command: a model with planes goes to .glb and back with its planes; a model
//! without planes written as a PLY beside an older planes.json does not inherit that file's
//! planes.
use std::path::Path;
use std::process::Command;
use trgs_core::fixtures::{SceneSpec, random_scene};
use trgs_core::io::{load_model, write_planes_json, write_ply};
use trgs_core::scratch::ScratchDir;

fn convert(from: &Path, to: &Path) {
    let out = Command::new(env!("CARGO_BIN_EXE_convert")).arg(from).arg(to).output().expect("run");
    assert!(out.status.success(), "convert: {}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn planes_travel_with_the_model_and_stale_ones_are_replaced() {
    let dir = ScratchDir::new("convert-cli");
    let s = random_scene(&SceneSpec { planes: 2, gaussians: 50, ..SceneSpec::default() });
    let (with, without) = (dir.join("with"), dir.join("without"));
    std::fs::create_dir_all(&with).expect("dir");
    std::fs::create_dir_all(&without).expect("dir");
    write_ply(&with.join("model.ply"), &s.gaussians.cast()).expect("ply");
    write_planes_json(&with.join("planes.json"), &s.planes).expect("planes");
    write_ply(&without.join("model.ply"), &s.gaussians.cast()).expect("ply");

    // With planes: PLY -> GLB -> PLY in a new folder keeps both planes.
    convert(&with, &dir.join("model.glb"));
    let back = dir.join("back");
    std::fs::create_dir_all(&back).expect("dir");
    convert(&dir.join("model.glb"), &back.join("model.ply"));
    assert_eq!(load_model(&back, None).expect("back").planes.len(), 2);

    // Without planes, written over that folder: its planes.json must not survive as this
    // model's planes.
    convert(&without.join("model.ply"), &back.join("model.ply"));
    assert!(load_model(&back, None).expect("stale").planes.is_empty());
}
