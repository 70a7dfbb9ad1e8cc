//! A run folder belongs to one run at a time, and nothing in it passes as a result it is not:
//! a second run in a folder in use is refused; a new run sets a finished run's files aside and
//! marks the folder unfinished until its own results are written, so `eval` and `report` refuse
//! it meanwhile; Ctrl-C says what was saved; `--resume` tells a missing, unreadable, foreign or
//! tampered checkpoint apart.
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};
use trgs_core::scratch::ScratchDir;
use trgs_synthetic::{SyntheticConfig, generate, write_dataset};
use trgs_train::checkpoint::{CHECKPOINT_FILE, read_checkpoint, write_checkpoint};

const ITERATIONS: u32 = 30;

fn train(data: Option<&Path>, out: &Path, extra: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_train"));
    if let Some(d) = data {
        c.arg("--data").arg(d);
    }
    c.arg("--out").arg(out).args(extra);
    c
}

/// A run of the small scene that checkpoints every 5 steps.
fn start_run(data: &Path, out: &Path) -> Child {
    let steps = ITERATIONS.to_string();
    train(Some(data), out, &["--iterations", &steps, "--checkpoint-every", "5"])
        .args(["--eval-every", &steps, "--sh-degree", "0"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start train")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn failure(output: &Output) -> String {
    assert!(!output.status.success(), "expected a refusal: {}", text(&output.stdout));
    text(&output.stderr)
}

fn success(output: &Output) -> String {
    let stdout = text(&output.stdout);
    assert!(output.status.success(), "{stdout}\n{}", text(&output.stderr));
    stdout
}

/// Wait until `child` has written a checkpoint at step 5 or later; None if it ended first.
fn wait_for_checkpoint(child: &mut Child, out: &Path) -> Option<u32> {
    let t0 = Instant::now();
    loop {
        if let Ok(ck) = read_checkpoint(&out.join(CHECKPOINT_FILE))
            && ck.step >= 5
            && ck.step < ITERATIONS
        {
            return Some(ck.step);
        }
        if child.try_wait().expect("wait").is_some() {
            return None;
        }
        assert!(t0.elapsed() < Duration::from_secs(600), "no checkpoint after 10 minutes");
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn logged_steps(out: &Path) -> Vec<u64> {
    std::fs::read_to_string(out.join("log.jsonl"))
        .expect("log.jsonl")
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter_map(|v| v.get("step").and_then(serde_json::Value::as_u64))
        .collect()
}

fn eval(data: &Path, model: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_trgs"))
        .arg("eval")
        .arg("--model")
        .arg(model)
        .arg("--data")
        .arg(data)
        .output()
        .expect("eval")
}

#[test]
fn a_run_folder_holds_one_run_and_never_stale_results() {
    let dir = ScratchDir::new("run-folder-cli");
    let data = dir.join("data");
    write_dataset(&generate(&SyntheticConfig::small()), &data).expect("dataset");
    let out = dir.join("run");
    a_second_run_in_a_folder_in_use_is_refused(&data, &out);
    let first_model = std::fs::read(out.join("model.ply")).expect("the first run's model");
    let aside = an_interrupted_new_run_leaves_no_stale_results(&data, &out);
    assert_eq!(std::fs::read(aside.join("model.ply")).expect("kept"), first_model);
    resume_tells_bad_checkpoints_apart(&out);
    let stdout = success(&train(None, &out, &["--resume"]).output().expect("resume"));
    assert!(stdout.contains("resuming"), "{stdout}");
    success(&eval(&data, &out));
}

/// Two runs in one --out: the second is refused at once, naming the first's process, and the
/// first finishes with every step logged once.
fn a_second_run_in_a_folder_in_use_is_refused(data: &Path, out: &Path) {
    let mut first = start_run(data, out);
    let t0 = Instant::now();
    while std::fs::read_to_string(out.join(trgs_train::run::LOCK_FILE))
        .map_or(true, |t| t.is_empty())
    {
        assert!(first.try_wait().expect("wait").is_none(), "the first run ended early");
        assert!(t0.elapsed() < Duration::from_secs(120), "the first run took no lock");
        std::thread::sleep(Duration::from_millis(10));
    }
    let second = start_run(data, out).wait_with_output().expect("second run");
    let stderr = failure(&second);
    assert!(stderr.contains("in use by another training run"), "{stderr}");
    assert!(stderr.contains(&format!("process {}", first.id())), "{stderr}");
    success(&first.wait_with_output().expect("first run"));
    let steps = logged_steps(out);
    assert_eq!(steps, (1..=u64::from(ITERATIONS)).collect::<Vec<_>>(), "one run's steps, once");
    success(&eval(data, out));
}

/// A new run in the finished run's folder, interrupted by Ctrl-C after a checkpoint: it says
/// what was saved; the finished run's files were set aside (returned), and until the new run
/// finishes `eval` and `report` refuse the folder as unfinished.
fn an_interrupted_new_run_leaves_no_stale_results(data: &Path, out: &Path) -> PathBuf {
    let mut run = start_run(data, out);
    let step = wait_for_checkpoint(&mut run, out).expect("the run ended before a checkpoint");
    interrupt(&run);
    let output = run.wait_with_output().expect("interrupted run");
    let stdout = text(&output.stdout);
    let stderr = failure(&output);
    assert!(stdout.contains("the previous run's files"), "{stdout}");
    let aside = out.join("previous-1");
    assert!(stdout.contains(&aside.display().to_string()), "{stdout}");
    // The checkpoint the message names is the one on disk (the run may have written a later
    // one between the wait and the signal).
    let saved = read_checkpoint(&out.join(CHECKPOINT_FILE)).expect("checkpoint").step;
    assert!(saved >= step, "checkpoint {saved} after {step}");
    let said = format!("interrupted: the checkpoint of step {saved} of {ITERATIONS} is saved");
    assert!(stderr.contains(&said) && stderr.contains("--resume"), "{stderr}");
    for file in ["model.ply", "planes.json", "metrics.json", "renders"] {
        assert!(!out.join(file).exists(), "{file} of the old run is not in the folder");
        assert!(aside.join(file).exists(), "{file} was set aside");
    }
    let stderr = failure(&eval(data, out));
    assert!(stderr.contains("unfinished training run") && stderr.contains("--resume"), "{stderr}");
    let report = Command::new(env!("CARGO_BIN_EXE_trgs"))
        .arg("report")
        .arg(out)
        .arg("--plot")
        .arg(out.join("report.png"))
        .output()
        .expect("report");
    let stderr = failure(&report);
    assert!(stderr.contains("unfinished training run"), "{stderr}");
    aside
}

/// Ctrl-C to `child`.
fn interrupt(child: &Child) {
    let status =
        Command::new("kill").args(["-INT", &child.id().to_string()]).status().expect("kill -INT");
    assert!(status.success());
}

/// `--resume` on a missing checkpoint, a folder in its place, a foreign file, a symlink loop,
/// a newer format and a step past the run's end: each refused by what it is, before any
/// training; the checkpoint is put back afterwards.
fn resume_tells_bad_checkpoints_apart(out: &Path) {
    let path = out.join(CHECKPOINT_FILE);
    let kept = out.join("kept.trgs");
    std::fs::rename(&path, &kept).expect("move the checkpoint away");
    let refused = |what: &str| failure(&train(None, out, &["--resume"]).output().expect(what));
    let stderr = refused("missing");
    assert!(stderr.contains("no checkpoint to continue from") && stderr.contains("missing"));
    std::fs::create_dir(&path).expect("a folder in its place");
    let stderr = refused("folder");
    assert!(stderr.contains("is a folder, not a checkpoint file"), "{stderr}");
    std::fs::remove_dir(&path).expect("remove the folder");
    std::fs::write(&path, b"P6\n64 48\n255\n").expect("a foreign file");
    let stderr = refused("foreign");
    assert!(stderr.contains("cannot be read") && stderr.contains("not a trgs checkpoint"));
    std::fs::write(&path, b"trgs-checkpoint 9\n{}\n").expect("a newer format");
    let stderr = refused("newer");
    assert!(stderr.contains("written by a newer trgs"), "{stderr}");
    std::fs::remove_file(&path).expect("remove");
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(&path, &path).expect("a symlink loop");
        let stderr = refused("symlink loop");
        assert!(stderr.contains("cannot be read") && !stderr.contains("no checkpoint"));
        std::fs::remove_file(&path).expect("remove the link");
    }
    let mut ck = read_checkpoint(&kept).expect("the kept checkpoint");
    ck.step = 10 * ITERATIONS;
    write_checkpoint(&path, &ck).expect("a tampered checkpoint");
    let stderr = refused("past the end");
    assert!(stderr.contains(&format!("past the {ITERATIONS} steps")), "{stderr}");
    std::fs::rename(&kept, &path).expect("put the checkpoint back");
}
