//! `train` on a scene without glass masks creates no plane: it says so, trains plain 3DGS (no
//! mirrored pass, so no reflection layer) and writes an empty `planes.json`, and its metrics
//! count no plane. That its PSNR then equals a `--no-planes` run's is measured on the full-size
//! scene in docs/RESULTS.md, "Without glass" (GPU float atomics make two runs differ a little).
use std::process::Command;
use trgs_core::scratch::ScratchDir;
use trgs_synthetic::{SyntheticConfig, generate, write_dataset};

#[test]
fn scene_without_masks_trains_no_plane() {
    let dir = ScratchDir::new("no-glass-cli");
    let data = dir.join("data");
    write_dataset(&generate(&SyntheticConfig::small().without_glass()), &data).expect("dataset");
    assert!(!data.join("glass_masks").exists(), "the scene without glass has masks");
    let out = dir.join("run");
    let run = Command::new(env!("CARGO_BIN_EXE_train"))
        .arg("--data")
        .arg(&data)
        .arg("--out")
        .arg(&out)
        .args(["--iterations", "12", "--eval-every", "12", "--sh-degree", "0"])
        .output()
        .expect("run train");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&run.stderr));
    assert!(stdout.contains("no glass masks: no reflection planes"), "{stdout}");
    let planes: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("planes.json")).expect("planes"))
            .expect("planes.json");
    assert_eq!(planes["planes"].as_array().map(Vec::len), Some(0), "{planes}");
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).expect("metrics"))
            .expect("metrics.json");
    assert_eq!(metrics["planes"], 0, "{metrics}");
    assert!(metrics["psnr"].as_f64().is_some_and(f64::is_finite), "{metrics}");
}
