//! `train` killed mid-run and continued with `--resume`: the run finishes at its planned step
//! count with its own settings, the log has every step once, and the checkpoint holds the planes
//! that stage 1 initialised; `eval` of the result reproduces the run's own test PSNR. (That the
//! resumed result matches an uninterrupted run is measured on the full-size scene in
//! docs/RESULTS.md, "Resume"; GPU float atomics make any two runs differ a
//! little, so a small test could not tell a resume bug from that noise.)
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};
use trgs_core::io::ColmapModel;
use trgs_core::scratch::ScratchDir;
use trgs_synthetic::{SyntheticConfig, generate, write_dataset};
use trgs_train::checkpoint::{CHECKPOINT_FILE, read_checkpoint};

fn tmp(name: &str) -> ScratchDir {
    ScratchDir::new(&format!("resume-{name}"))
}

fn logged_steps(log: &Path) -> Vec<u64> {
    std::fs::read_to_string(log)
        .expect("log.jsonl")
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter_map(|v| v.get("step").and_then(serde_json::Value::as_u64))
        .collect()
}

#[test]
fn killed_run_resumes_to_the_end() {
    let dir = tmp("kill");
    let data = dir.join("data");
    write_dataset(&generate(&SyntheticConfig::small()), &data).expect("dataset");
    let out = dir.join("run");
    let iterations = 40;
    let killed_at = kill_after_plane_checkpoint(&data, &out, iterations);
    let metrics = resume_to_the_end(&out, iterations, killed_at);
    let evaluated = eval_reproduces_the_run(&data, &out, &metrics);
    let train_names =
        eval_on_the_training_views(&dir.join("train_renders"), &data, &out, &evaluated);
    resume_with_other_settings_is_refused(&out);
    resuming_a_finished_run_rewrites_its_results(&out, iterations, &metrics);
    resume_on_changed_training_views_is_refused(&data, &out, &train_names[0]);
    resume_on_a_moved_camera_is_refused(&data, &out, &train_names[1]);
    new_run_sets_the_old_checkpoint_aside(&data, &out);
}

/// `train` with the folder's settings via `--resume` and any `extra` arguments.
fn resume(out: &Path, extra: &[&str], what: &str) -> Output {
    Command::new(env!("CARGO_BIN_EXE_train"))
        .arg("--out")
        .arg(out)
        .arg("--resume")
        .args(extra)
        .output()
        .expect(what)
}

/// `file` in `out` as JSON.
fn read_json(out: &Path, file: &str, what: &str) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join(file)).expect(file)).expect(what)
}

/// Starts a run of `iterations` steps and kills it once a checkpoint after the plane
/// initialisation (step 4 of 40) exists; returns the step of the checkpoint it left.
fn kill_after_plane_checkpoint(data: &Path, out: &Path, iterations: u32) -> u32 {
    let mut child = Command::new(env!("CARGO_BIN_EXE_train"))
        .arg("--data")
        .arg(data)
        .arg("--out")
        .arg(out)
        .args(["--iterations", &iterations.to_string(), "--checkpoint-every", "5"])
        .args(["--eval-every", "20", "--sh-degree", "1"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start train");
    let ckpt = out.join(CHECKPOINT_FILE);
    let t0 = Instant::now();
    let killed_at = loop {
        if let Ok(ck) = read_checkpoint(&ckpt)
            && ck.step >= 10
        {
            child.kill().expect("kill");
            let _ = child.wait();
            break ck.step;
        }
        if let Some(status) = child.try_wait().expect("wait") {
            panic!("train exited ({status}) before it could be killed");
        }
        assert!(t0.elapsed() < Duration::from_secs(600), "no checkpoint after 10 minutes");
        std::thread::sleep(Duration::from_millis(50));
    };
    let ck = read_checkpoint(&ckpt).expect("checkpoint after the kill");
    assert!(ck.step >= killed_at && ck.step < iterations);
    assert_eq!(ck.planes.len(), 1, "the checkpoint holds the initialised plane");
    assert!(!out.join("metrics.json").exists(), "the killed run did not finish");
    ck.step
}

/// `--resume` continues from the checkpoint at `step` to the planned end, logging every step
/// once; returns the run's metrics.
fn resume_to_the_end(out: &Path, iterations: u32, step: u32) -> serde_json::Value {
    // What a kill during a checkpoint write leaves behind is removed when the run resumes.
    let stale = out.join(format!(".{CHECKPOINT_FILE}.999.0.tmp"));
    std::fs::write(&stale, b"half a checkpoint").expect("stale temporary");
    let resumed = resume(out, &[], "resume");
    let stdout = String::from_utf8_lossy(&resumed.stdout);
    assert!(
        resumed.status.success(),
        "resume failed: {stdout}\n{}",
        String::from_utf8_lossy(&resumed.stderr)
    );
    assert!(stdout.contains(&format!("at step {step} of {iterations}")), "{stdout}");
    assert!(!stale.exists(), "the stale temporary file was removed");
    let metrics = read_json(out, "metrics.json", "metrics JSON");
    assert_eq!(metrics["steps"], iterations);
    assert_eq!(metrics["planes"], 1);
    assert!(metrics["psnr"].as_f64().is_some_and(f64::is_finite));
    let steps = logged_steps(&out.join("log.jsonl"));
    assert_eq!(steps, (1..=u64::from(iterations)).collect::<Vec<_>>(), "every step logged once");
    metrics
}

/// `eval` of the finished run reproduces its final test PSNR from the files it wrote; returns
/// what it wrote to eval.json.
fn eval_reproduces_the_run(
    data: &Path,
    out: &Path,
    metrics: &serde_json::Value,
) -> serde_json::Value {
    let eval = Command::new(env!("CARGO_BIN_EXE_trgs"))
        .arg("eval")
        .arg("--model")
        .arg(out)
        .arg("--data")
        .arg(data)
        .output()
        .expect("eval");
    assert!(eval.status.success(), "{}", String::from_utf8_lossy(&eval.stderr));
    let evaluated = read_json(out, "eval.json", "eval JSON");
    let (a, b) = (evaluated["psnr"].as_f64(), metrics["psnr"].as_f64());
    assert!(
        a.zip(b).is_some_and(|(a, b)| (a - b).abs() < 1e-3),
        "eval PSNR {a:?} against the run's {b:?}"
    );
    // The synthetic scene has true transmission images: both split the final image's error
    // into where the glass reflects and elsewhere, score the transmission layer in the first,
    // and agree.
    for key in [
        "reflection_region_psnr",
        "elsewhere_psnr",
        "reflection_region_share",
        "transmission_region_psnr",
    ] {
        let (a, b) = (evaluated["truth"][key].as_f64(), metrics["truth"][key].as_f64());
        assert!(
            a.zip(b).is_some_and(|(a, b)| a.is_finite() && (a - b).abs() < 1e-3),
            "{key}: eval {a:?} against the run's {b:?}"
        );
    }
    let share = evaluated["truth"]["reflection_region_share"].as_f64().unwrap_or(0.0);
    assert!(share > 0.01 && share < 0.9, "reflection region share {share}");
    evaluated
}

/// `eval --split train` measures the views the run trained on, writes them beside eval.json
/// without replacing it (still `evaluated`), and `--renders` writes each one's render and
/// layers; returns the training views' file names, sorted.
fn eval_on_the_training_views(
    renders: &Path,
    data: &Path,
    out: &Path,
    evaluated: &serde_json::Value,
) -> Vec<String> {
    let eval = Command::new(env!("CARGO_BIN_EXE_trgs"))
        .arg("eval")
        .arg("--model")
        .arg(out)
        .arg("--data")
        .arg(data)
        .args(["--split", "train", "--renders"])
        .arg(renders)
        .output()
        .expect("eval --split train");
    assert!(eval.status.success(), "{}", String::from_utf8_lossy(&eval.stderr));
    let on_train = read_json(out, "eval_train.json", "eval JSON");
    assert_eq!(on_train["split"], "train");
    let train_names = training_view_names(data);
    let measured: Vec<String> = on_train["views"]
        .as_array()
        .expect("views")
        .iter()
        .map(|v| v["name"].as_str().expect("name").to_string())
        .collect();
    assert_eq!(measured, train_names, "the training views, and only those");
    for name in &train_names {
        let stem = name.trim_end_matches(".png");
        assert!(renders.join(name).is_file(), "render of {name}");
        assert!(renders.join(format!("layers/{stem}_transmission.png")).is_file(), "{stem}");
    }
    // The model without its planes, and against its own renders: named so, beside eval.json.
    for (extra, file) in [
        (vec!["--no-planes"], "eval_no-planes.json"),
        (vec!["--reference", &out.display().to_string()], "eval_reference.json"),
    ] {
        let scored = Command::new(env!("CARGO_BIN_EXE_trgs"))
            .arg("eval")
            .arg("--model")
            .arg(out)
            .arg("--data")
            .arg(data)
            .args(&extra)
            .output()
            .expect("eval");
        assert!(scored.status.success(), "{}", String::from_utf8_lossy(&scored.stderr));
        let json = read_json(out, file, "eval JSON");
        assert_eq!(json["no_planes"], extra[0] == "--no-planes", "{file}");
    }
    let again = read_json(out, "eval.json", "eval JSON");
    assert_eq!(&again, evaluated, "eval.json (the test views) is left as it was");
    train_names
}

/// The dataset's images not listed in test_views.txt, sorted.
fn training_view_names(data: &Path) -> Vec<String> {
    let test_names: Vec<String> = std::fs::read_to_string(data.join("test_views.txt"))
        .expect("test_views.txt")
        .lines()
        .map(|l| l.trim().to_string())
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .collect();
    let mut train_names: Vec<String> = std::fs::read_dir(data.join("images"))
        .expect("images")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|n| !test_names.contains(n))
        .collect();
    train_names.sort();
    train_names
}

/// Settings come from the checkpoint: changing them on resume is refused.
fn resume_with_other_settings_is_refused(out: &Path) {
    let refused = resume(out, &["--iterations", "80"], "run");
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("drop --iterations"));
}

/// The finished run left its final state: `--resume` writes the same results again instead
/// of training on from the last intermediate checkpoint.
fn resuming_a_finished_run_rewrites_its_results(
    out: &Path,
    iterations: u32,
    metrics: &serde_json::Value,
) {
    let ckpt = out.join(CHECKPOINT_FILE);
    assert_eq!(read_checkpoint(&ckpt).expect("final checkpoint").step, iterations);
    let again = resume(out, &[], "resume a finished run");
    let stdout = String::from_utf8_lossy(&again.stdout);
    assert!(again.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&again.stderr));
    assert!(stdout.contains(&format!("finished at step {iterations}")), "{stdout}");
    assert_eq!(logged_steps(&out.join("log.jsonl")).len(), iterations as usize, "no step rerun");
    let rewritten = read_json(out, "metrics.json", "metrics JSON");
    let (a, b) = (rewritten["psnr"].as_f64(), metrics["psnr"].as_f64());
    assert!(a.zip(b).is_some_and(|(a, b)| (a - b).abs() < 1e-3), "{a:?} against {b:?}");
}

/// A dataset whose training views changed (`train_name` moved to the test split) is refused
/// by name, not indexed out of bounds; the split is restored afterwards.
fn resume_on_changed_training_views_is_refused(data: &Path, out: &Path, train_name: &str) {
    let split = data.join("test_views.txt");
    let original = std::fs::read_to_string(&split).expect("test_views.txt");
    std::fs::write(&split, format!("{original}\n{train_name}\n")).expect("edit split");
    let refused = resume(out, &[], "resume on changed data");
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success());
    assert!(
        stderr.contains("training views") && stderr.contains(&data.display().to_string()),
        "{stderr}"
    );
    std::fs::write(&split, original).expect("restore split");
}

/// A dataset whose training view `train_name` kept its name but moved (a COLMAP model made
/// again) is refused by that name; the model is restored afterwards.
fn resume_on_a_moved_camera_is_refused(data: &Path, out: &Path, train_name: &str) {
    let sparse = data.join("sparse").join("0");
    let mut model = ColmapModel::read(&sparse).expect("COLMAP model");
    let original = model.clone();
    let image = model.images.iter_mut().find(|i| i.name == train_name).expect("the view");
    image.tvec[0] += 0.05;
    model.write_binary(&sparse).expect("moved model");
    let refused = resume(out, &[], "resume on a moved camera");
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success());
    assert!(stderr.contains(train_name) && stderr.contains("pose or lens changed"), "{stderr}");
    original.write_binary(&sparse).expect("restore model");
}

/// A new run in the same folder sets the finished run's checkpoint aside first, so that a
/// `--resume` after the new run stopped early cannot continue the old one.
fn new_run_sets_the_old_checkpoint_aside(data: &Path, out: &Path) {
    let fresh = Command::new(env!("CARGO_BIN_EXE_train"))
        .arg("--data")
        .arg(data)
        .arg("--out")
        .arg(out)
        .args(["--iterations", "2", "--sh-degree", "0"])
        .output()
        .expect("a new run");
    let stdout = String::from_utf8_lossy(&fresh.stdout);
    assert!(fresh.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&fresh.stderr));
    assert!(stdout.contains("the previous run's files"), "{stdout}");
    assert!(out.join("previous-1").join(CHECKPOINT_FILE).is_file(), "set aside, not lost");
    let ckpt = out.join(CHECKPOINT_FILE);
    assert_eq!(read_checkpoint(&ckpt).expect("the new run's checkpoint").step, 2);
}
