//! The `export` command: `--full` carries a model's planes to .glb and back, and a model
//! without planes written as a PLY beside an older planes.json does not inherit that file's
//! planes; by default a model with planes is baked into plain Gaussians (no glass, no planes,
//! mirrored copies added), and .spz files round-trip through trgs.
use std::path::Path;
use std::process::Command;
use trgs_core::Population;
use trgs_core::fixtures::{SceneSpec, random_scene};
use trgs_core::io::{load_model, write_cameras_json, write_planes_json, write_ply};
use trgs_core::scratch::ScratchDir;

fn run_export(args: &[&Path]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_trgs")).arg("export").args(args).output().expect("run")
}

fn export(args: &[&Path]) -> String {
    let out = run_export(args);
    assert!(out.status.success(), "export: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// What `export` says on stderr when it refuses `args`.
fn refused(args: &[&Path]) -> String {
    let out = run_export(args);
    assert!(!out.status.success(), "export {args:?} was not refused");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn planes_travel_with_the_full_model_and_stale_ones_are_replaced() {
    let dir = ScratchDir::new("export-cli");
    let s = random_scene(&SceneSpec { planes: 2, gaussians: 50, ..SceneSpec::default() });
    let (with, without) = (dir.join("with"), dir.join("without"));
    std::fs::create_dir_all(&with).expect("dir");
    std::fs::create_dir_all(&without).expect("dir");
    write_ply(&with.join("model.ply"), &s.gaussians.cast()).expect("ply");
    write_planes_json(&with.join("planes.json"), &s.planes).expect("planes");
    write_ply(&without.join("model.ply"), &s.gaussians.cast()).expect("ply");
    let full = Path::new("--full");

    // With planes: PLY -> GLB -> PLY in a new folder keeps both planes.
    export(&[&with, &dir.join("model.glb"), full]);
    let back = dir.join("back");
    std::fs::create_dir_all(&back).expect("dir");
    export(&[&dir.join("model.glb"), &back.join("model.ply"), full]);
    assert_eq!(load_model(&back, None).expect("back").planes.len(), 2);

    // Without planes, written over that folder: its planes.json must not survive as this
    // model's planes. Its glass Gaussians, whose planes.json was not copied, do not reach a
    // plain viewer.
    let said = export(&[&without.join("model.ply"), &back.join("model.ply")]);
    assert!(said.contains("glass is left out"), "{said}");
    let plain = load_model(&back, None).expect("stale");
    assert!(plain.planes.is_empty());
    assert!(plain.gaussians.populations.iter().all(|&p| p == Population::Primary));
    let primaries = s.gaussians.populations.iter().filter(|&&p| p == Population::Primary);
    assert_eq!(plain.gaussians.len(), primaries.count());
    // With --full the glass is kept for trgs.
    export(&[&without.join("model.ply"), &back.join("model.ply"), full]);
    assert_eq!(load_model(&back, None).expect("full").gaussians.len(), s.gaussians.len());

    // A bake onto its own model would replace it: refused.
    assert!(refused(&[&with, &with.join("model.ply")]).contains("the model itself"));
}

#[test]
fn a_model_with_planes_is_baked_for_plain_viewers_and_spz_round_trips() {
    let dir = ScratchDir::new("export-bake-cli");
    let s = random_scene(&SceneSpec {
        planes: 1,
        gaussians: 400,
        width: 64,
        height: 48,
        ..SceneSpec::default()
    });
    let run = dir.join("run");
    std::fs::create_dir_all(&run).expect("dir");
    write_ply(&run.join("model.ply"), &s.gaussians.cast()).expect("ply");
    write_planes_json(&run.join("planes.json"), &s.planes).expect("planes");

    // Baking needs the views: refused by name without a cameras.json.
    let stderr = refused(&[&run, &dir.join("baked.ply")]);
    assert!(stderr.contains("cameras.json") && stderr.contains("--full"), "{stderr}");

    write_cameras_json(&run.join("cameras.json"), std::slice::from_ref(&s.camera)).expect("cams");
    let said = export(&[&run, &dir.join("baked.ply")]);
    assert!(said.contains("PSNR") && said.contains("glass Gaussians left out"), "{said}");
    let baked = load_model(&dir.join("baked.ply"), None).expect("baked");
    assert!(baked.planes.is_empty(), "no planes.json is written beside a baked model");
    assert!(baked.gaussians.populations.iter().all(|&p| p == Population::Primary));
    let glass = s.gaussians.populations.iter().filter(|&&p| p == Population::Glass).count();
    assert!(glass > 0);
    assert_ne!(baked.gaussians.len(), s.gaussians.len() - glass, "mirrored copies were added");

    // SPZ: written, read back by trgs (export to PLY) with the same count.
    export(&[&run, &dir.join("baked.spz")]);
    export(&[&dir.join("baked.spz"), &dir.join("from-spz.ply")]);
    let back = load_model(&dir.join("from-spz.ply"), None).expect("from spz");
    assert_eq!(back.gaussians.len(), baked.gaussians.len());
    let stderr = refused(&[Path::new("--full"), &run, &dir.join("full.spz")]);
    assert!(stderr.contains("--full keeps the planes"), "{stderr}");
}
