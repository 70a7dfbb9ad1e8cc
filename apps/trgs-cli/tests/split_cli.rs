//! The `split` command on a synthetic glass scene: every view trains a block, each test view is
//! in exactly one block, the blocks' points cover the capture's and overlap at the seam, every
//! block folder is a scene folder trgs opens, and the manifest lists them.
use std::collections::HashSet;
use std::process::Command;
use trgs_core::io::{ColmapModel, SceneFolder};
use trgs_core::scratch::ScratchDir;
use trgs_synthetic::{SyntheticConfig, generate, write_dataset};

#[test]
fn a_scene_splits_into_block_folders_that_cover_it() {
    let dir = ScratchDir::new("split-cli");
    let scene = dir.join("scene");
    write_dataset(&generate(&SyntheticConfig::small()), &scene).expect("scene");
    let whole = SceneFolder::open(&scene).expect("the scene");
    let out = dir.join("blocks");
    let run = Command::new(env!("CARGO_BIN_EXE_trgs"))
        .arg("split")
        .arg(&scene)
        .args(["--blocks", "2", "--out"])
        .arg(&out)
        .output()
        .expect("run");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{stdout}{}", String::from_utf8_lossy(&run.stderr));

    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("blocks.json")).expect("manifest"))
            .expect("JSON");
    let blocks = manifest["blocks"].as_array().expect("blocks");
    assert_eq!(blocks.len(), 2);
    let (mut trained, mut tested, mut points) = (HashSet::new(), Vec::new(), Vec::new());
    for b in blocks {
        let folder = out.join(b["folder"].as_str().expect("folder"));
        let block = SceneFolder::open(&folder).expect("a block is a scene folder");
        let test: HashSet<&String> = block.test_views.iter().collect();
        for v in &block.views {
            assert!(v.image_path.is_file(), "{}", v.image_path.display());
            if test.contains(&v.camera.name) {
                tested.push(v.camera.name.clone());
            } else {
                trained.insert(v.camera.name.clone());
            }
        }
        let model = ColmapModel::read(&folder.join("sparse/0")).expect("sparse");
        points.extend(model.points.iter().map(|p| p.id));
        assert_eq!(b["points"].as_u64(), Some(model.points.len() as u64));
    }
    let all_test: HashSet<&String> = whole.test_views.iter().collect();
    let mut tested_sorted = tested.clone();
    tested_sorted.sort();
    let mut expected: Vec<String> = whole.test_views.clone();
    expected.sort();
    assert_eq!(tested_sorted, expected, "each test view in one block, once");
    for v in &whole.views {
        if !all_test.contains(&v.camera.name) {
            assert!(trained.contains(&v.camera.name), "{} trains no block", v.camera.name);
        }
    }
    let unique: HashSet<u64> = points.iter().copied().collect();
    let whole_points = ColmapModel::read(&scene.join("sparse/0")).expect("sparse").points.len();
    assert!(unique.len() * 100 >= whole_points * 95, "{} of {whole_points}", unique.len());
    assert!(points.len() > unique.len(), "the blocks overlap");
}

#[test]
fn bad_arguments_are_refused_by_name() {
    let dir = ScratchDir::new("split-cli-bad");
    let refused = |args: &[&str]| {
        let out =
            Command::new(env!("CARGO_BIN_EXE_trgs")).arg("split").args(args).output().expect("run");
        assert!(!out.status.success(), "{args:?}");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let d = dir.to_string_lossy().into_owned();
    assert!(refused(&[&d, "--out", "x", "--blocks", "0"]).contains("--blocks"));
    assert!(refused(&[&d, "--out", "x", "--blocks", "2", "--min-share", "2"]).contains("[0, 1]"));
    assert!(refused(&[&d, "--out", "x", "--blocks", "2"]).contains(&d));
}
