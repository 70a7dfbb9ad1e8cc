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

#[test]
fn trained_blocks_merge_into_one_run() {
    use trgs_core::Population;
    use trgs_core::io::{load_model, write_planes_json, write_ply};
    use trgs_core::scene::{Gaussians, Material, ReflectionPlane};
    let dir = ScratchDir::new("merge-cli");
    let scene = dir.join("scene");
    let synthetic = generate(&SyntheticConfig::small());
    write_dataset(&synthetic, &scene).expect("scene");
    let blocks = dir.join("blocks");
    let split = Command::new(env!("CARGO_BIN_EXE_trgs"))
        .arg("split")
        .arg(&scene)
        .args(["--blocks", "2", "--out"])
        .arg(&blocks)
        .output()
        .expect("split");
    assert!(split.status.success(), "{}", String::from_utf8_lossy(&split.stderr));
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(blocks.join("blocks.json")).expect("read"))
            .expect("JSON");
    let axis = |k: usize| -> [f64; 3] {
        let a = &manifest["axes"][k];
        [0, 1, 2].map(|i| a[i].as_f64().expect("axis"))
    };
    let (a0, a1) = (axis(0), axis(1));
    let centre = |b: usize| -> [f64; 2] {
        let c = &manifest["blocks"][b]["centre"];
        [c[0].as_f64().expect("c"), c[1].as_f64().expect("c")]
    };
    // A world point at ground coordinates (u, v).
    let at = |u: f64, v: f64| -> [f32; 3] { [0, 1, 2].map(|i| (u * a0[i] + v * a1[i]) as f32) };
    let (c0, c1) = (centre(0), centre(1));
    let mid = [(c0[0] + c1[0]) / 2.0, (c0[1] + c1[1]) / 2.0];
    // Each block's run: one Gaussian at each centre (each block keeps its own), and half of one
    // pane across the seam.
    let runs = dir.join("runs");
    for b in 0..2 {
        let run = runs.join(format!("block_{b}"));
        std::fs::create_dir_all(&run).expect("run");
        let mut g = Gaussians::empty(0);
        for c in [c0, c1] {
            g.push(
                at(c[0], c[1]),
                [1.0, 0.0, 0.0, 0.0],
                [-3.0; 3],
                0.0,
                &[[0.0; 3]],
                Population::Primary,
            );
        }
        write_ply(&run.join("model.ply"), &g).expect("ply");
        let side = if b == 0 { -0.5 } else { 0.5 };
        let along = glam::DVec3::from_array(a0);
        let pane_centre =
            glam::DVec3::from_array([0, 1, 2].map(|i| f64::from(at(mid[0], mid[1])[i])))
                + along * side;
        let normal = glam::DVec3::from_array(a1);
        let p = ReflectionPlane::new(pane_centre, normal, along, 1.0, 0.5, Material::Glass);
        // The second block also found the scene's window as it is.
        let planes = if b == 0 { vec![p] } else { vec![p, synthetic.planes[0]] };
        write_planes_json(&run.join("planes.json"), &planes).expect("planes");
    }
    let out = dir.join("merged");
    let merge = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_trgs"))
            .arg("merge")
            .arg(&blocks)
            .arg("--runs")
            .arg(&runs)
            .arg("--out")
            .arg(&out)
            .args(extra)
            .output()
            .expect("merge")
    };
    // A run whose views are not its block's (a run of an earlier split) is refused by name.
    let block_1 = manifest["blocks"][1]["folder"].as_str().expect("folder");
    let folder = SceneFolder::open(&blocks.join(block_1)).expect("block folder");
    let cameras: Vec<_> = folder.views.iter().skip(1).map(|v| v.camera.clone()).collect();
    let stale = runs.join("block_1").join("cameras.json");
    trgs_core::io::write_cameras_json(&stale, &cameras).expect("cameras");
    let refused = merge(&["--by-geometry"]);
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success());
    assert!(stderr.contains("block_1") && stderr.contains("1 of its"), "{stderr}");
    std::fs::remove_file(&stale).expect("remove");
    // By geometry the halves of one pane are one plane.
    let merged = merge(&["--by-geometry"]);
    let stdout = String::from_utf8_lossy(&merged.stdout);
    assert!(merged.status.success(), "{stdout}{}", String::from_utf8_lossy(&merged.stderr));
    let model = load_model(&out, None).expect("the merged run");
    assert_eq!(model.gaussians.len(), 2, "each block keeps the Gaussian on its own ground");
    assert_eq!(model.planes.len(), 2, "the halves of one pane are one plane: {stdout}");
    assert!((model.planes[0].width - 2.0).abs() < 1e-6);
    // Held against the scene's glass masks, the halves cover no glass and are left out; the
    // window stands.
    let merged = merge(&[]);
    let stdout = String::from_utf8_lossy(&merged.stdout);
    assert!(merged.status.success(), "{stdout}{}", String::from_utf8_lossy(&merged.stderr));
    let model = load_model(&out, None).expect("the merged run");
    assert_eq!(model.planes.len(), 1, "{stdout}");
    let truth = &synthetic.planes[0];
    let off = (model.planes[0].centre - truth.centre).length();
    assert!(off < 0.02 * truth.width.max(truth.height), "{off} off the window");
    assert!(stdout.contains("mask label 1, from block_1 plane 2"), "{stdout}");
    assert_eq!(stdout.matches("left out, covers no glass").count(), 2, "{stdout}");
    // The capture's test views that look across the seam, for eval to score apart.
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).expect("read"))
            .expect("JSON");
    let seams = metrics["seam_views"].as_array().expect("seam views");
    let tests = std::fs::read_to_string(scene.join("test_views.txt")).expect("test views");
    assert!(seams.iter().all(|v| tests.contains(v.as_str().expect("a name"))), "{seams:?}");
    // A block without a run is named.
    std::fs::remove_dir_all(runs.join("block_1")).expect("remove");
    let missing = merge(&[]);
    assert!(!missing.status.success());
    assert!(String::from_utf8_lossy(&missing.stderr).contains("no run of block_1"));
}
