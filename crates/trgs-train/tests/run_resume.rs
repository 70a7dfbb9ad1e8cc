//! A [`TrainingRun`] stopped after a checkpoint (dropped, as a kill would stop it) and continued
//! with [`TrainingRun::resume`]: it goes on from the checkpoint's step with the settings it
//! started with and the plane that stage 1 initialised, finishes at its planned step count, and
//! logs every step once; resuming the finished run writes its results again without training.
//! With exposure compensation on, its learned exposures are in the checkpoint and exposures.json.
//! And a run reports every densification it applies, those it pipelines a step late included.
use std::path::Path;
use trgs_core::scratch::ScratchDir;
use trgs_synthetic::{SyntheticConfig, generate, write_dataset};
use trgs_train::run::{ExposureMode, LOG_FILE};
use trgs_train::{RunConfig, RunEvent, RunOptions, TrainingRun};

fn logged_steps(log: &Path) -> Vec<u64> {
    std::fs::read_to_string(log)
        .expect("the log")
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter_map(|v| v.get("step").and_then(serde_json::Value::as_u64))
        .collect()
}

#[test]
fn a_stopped_run_resumes_through_the_library() {
    let dir = ScratchDir::new("run-resume");
    let data = dir.join("data");
    write_dataset(&generate(&SyntheticConfig::small()), &data).expect("dataset");
    let out = dir.join("run");
    let config = RunConfig {
        data: Some(data),
        out: out.clone(),
        iterations: 40,
        checkpoint_every: Some(5),
        eval_every: Some(20),
        sh_degree: 1,
        exposure: ExposureMode::On,
        // Kept through the checkpoint (no reset falls in 40 steps either way).
        opacity_reset_every: Some(0),
        ..RunConfig::default()
    };
    let mut run = TrainingRun::start(config.clone(), RunOptions::default()).expect("a new run");
    let mut planes = 0;
    let mut seeded = Vec::new();
    let stopped = loop {
        match run.next_event().expect("the run goes on").expect("a step") {
            RunEvent::PlaneCreated { .. } => planes += 1,
            RunEvent::Note(line) if line.contains("mirrored to its front") => seeded.push(line),
            RunEvent::CheckpointWritten { step, .. } if step >= 10 => break step,
            _ => {}
        }
    };
    assert_eq!(planes, 1, "stage 1 ends at step 4 of 40 with the glass plane");
    assert_eq!(seeded.len(), 1, "the plane's reflection seeds are reported: {seeded:?}");
    drop(run);
    assert!(!out.join("metrics.json").exists(), "the stopped run did not finish");

    let mut resumed = TrainingRun::resume(&out, RunOptions::default()).expect("resume");
    let note = match resumed.next_event() {
        Some(Ok(RunEvent::Note(line))) => line,
        other => panic!("expected a note first, got {other:?}"),
    };
    assert!(note.contains(&format!("at step {stopped} of 40")), "{note}");
    assert_eq!(resumed.trainer().step, stopped);
    assert_eq!(resumed.trainer().planes().len(), 1, "the checkpoint holds the plane");
    assert_eq!(resumed.config(), &config, "the run keeps its own settings");
    let mut steps = Vec::new();
    let summary = resumed
        .run_to_end(|e| {
            if let RunEvent::Step(s) = e {
                steps.push(s.step);
            }
        })
        .expect("the resumed run finishes");
    assert_eq!(steps, (stopped + 1..=40).collect::<Vec<_>>());
    assert_eq!((summary.steps, summary.planes), (40, 1));
    assert!(summary.last.psnr.is_finite());
    assert!(out.join("metrics.json").is_file() && out.join("model.ply").is_file());
    let metrics = std::fs::read_to_string(out.join("metrics.json")).expect("metrics.json");
    let metrics: serde_json::Value = serde_json::from_str(&metrics).expect("JSON");
    assert_eq!(
        metrics["densification"],
        serde_json::json!({
            "mode": "classic",
            "grow_fraction": 1.0,
            "opacity_reset_every": 0,
            "prune_scale": null
        }),
        "the metrics name the densification's knobs"
    );
    let exposures = std::fs::read_to_string(out.join("exposures.json")).expect("exposures.json");
    let exposures: serde_json::Value = serde_json::from_str(&exposures).expect("JSON");
    let views = exposures["views"].as_object().expect("a matrix per training view");
    let trained = resumed.data().train.len();
    assert_eq!(views.len(), trained);
    assert!(views.values().all(|m| m.as_array().is_some_and(|rows| rows.len() == 3)));
    let logged = logged_steps(&out.join(LOG_FILE));
    assert_eq!(logged, (1..=40).collect::<Vec<u64>>(), "every step logged once");
    // Every step line says what the step held: the frame's keys, GPU bytes and peak RAM.
    let text = std::fs::read_to_string(out.join(LOG_FILE)).expect("the log");
    for line in text.lines() {
        let v: serde_json::Value = serde_json::from_str(line).expect("a JSON line");
        if v.get("eval").is_none() {
            for field in ["keys", "gpu_bytes", "peak_ram_bytes"] {
                assert!(v[field].as_u64().is_some_and(|n| n > 0), "{field} in {line}");
            }
        }
    }

    // The machine's GPU budget for the views may be set anew; nothing else changes.
    let options = RunOptions { target_memory: Some(3), ..RunOptions::default() };
    let mut again = TrainingRun::resume(&out, options).expect("resume a finished run");
    assert_eq!(again.config().target_memory, Some(3));
    assert_eq!(again.trainer().targets().budget(), 3 << 20);
    assert_eq!(again.config(), &RunConfig { target_memory: Some(3), ..config.clone() });
    let mut trained = false;
    let summary =
        again.run_to_end(|e| trained |= matches!(e, RunEvent::Step(_))).expect("the results again");
    assert!(!trained, "a finished run takes no more steps");
    assert_eq!(summary.steps, 40);
    assert!(again.is_done());
}

/// Densification decided after steps the run pipelines lands at the next step's maintenance,
/// and is reported with the step after which it was applied; one decided just before the
/// planes start is applied then, and reported with the step that decided it.
#[test]
fn a_run_reports_every_densification_it_applies() {
    use trgs_train::densify::{ClassicSettings, Densification, DensifyEvent};
    let dir = ScratchDir::new("run-densify");
    let data = dir.join("data");
    write_dataset(&generate(&SyntheticConfig::small()), &data).expect("dataset");
    let config = RunConfig {
        data: Some(data),
        out: dir.join("run"),
        iterations: 40,
        checkpoint_every: Some(100),
        eval_every: Some(20),
        sh_degree: 1,
        ..RunConfig::default()
    };
    let mut run = TrainingRun::start(config, RunOptions::default()).expect("a new run");
    // Every 4 steps: at step 4, where stage 1 ends and the planes start, then at 8, 12 and 16
    // (pipelined: applied a step later) and 20 (an evaluation, taken whole: applied at once).
    let mut s = ClassicSettings::scaled(40);
    (s.from, s.every, s.until, s.opacity_reset_every) = (0, 4, 1000, 1000);
    run.trainer_mut().set_densification(&Densification::Classic(s)).expect("densification");
    let mut reported = Vec::new();
    loop {
        let event = run.next_event().expect("the run goes on").expect("a step");
        let RunEvent::Step(e) = event else { continue };
        let densified =
            e.stats.densified.iter().filter(|d| matches!(d, DensifyEvent::Densified(_)));
        reported.extend(densified.map(|_| e.step));
        if e.step == 20 {
            break;
        }
    }
    assert_eq!(reported, [4, 9, 13, 17, 20]);
    assert!(run.trainer().is_settled());
}
