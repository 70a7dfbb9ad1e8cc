//! Planes without masks: the proposal finds the synthetic scene's pane from its sparse points
//! and cameras alone and proposes nothing in the closed room; a `--planes auto` run proposes,
//! tries and decides its candidates, and says so in its events, log and metrics; a proposal
//! waits for a grown model, is tried again while it finds nothing, and a later one ends stage 1
//! where it proposes (kept across a resume).
use glam::DVec3;
use trgs_core::fit::{ProposalSettings, propose_planes};
use trgs_core::rng::Rng;
use trgs_core::scratch::ScratchDir;
use trgs_synthetic::{SyntheticConfig, generate, write_dataset};
use trgs_train::run::PlaneSource;
use trgs_train::{RunConfig, RunEvent, RunOptions, TrainingRun};

fn proposed(
    config: &SyntheticConfig,
) -> (Vec<trgs_core::fit::PlaneCandidate>, Vec<trgs_core::scene::ReflectionPlane>) {
    let scene = generate(config);
    let points: Vec<DVec3> = scene.points.iter().map(|(p, _)| DVec3::from_array(*p)).collect();
    let proposal =
        propose_planes(&points, &scene.cameras, &ProposalSettings::default(), &mut Rng::new(5));
    let kept = proposal.candidates.into_iter().filter(|c| c.rejected.is_none()).collect();
    (kept, scene.planes)
}

/// A `--planes auto` run of 40 steps on the small synthetic scene with `sparse_points`, in a
/// scratch folder named `name` (kept while the returned folder lives), writing to its `run/`.
fn auto_run(
    name: &str,
    sparse_points: usize,
    checkpoint_every: Option<u32>,
) -> (ScratchDir, RunConfig) {
    let dir = ScratchDir::new(name);
    let data = dir.join("data");
    let config = SyntheticConfig { sparse_points, ..SyntheticConfig::small() };
    write_dataset(&generate(&config), &data).expect("dataset");
    let config = RunConfig {
        data: Some(data),
        out: dir.join("run"),
        iterations: 40,
        checkpoint_every,
        sh_degree: 1,
        planes: Some(PlaneSource::Auto),
        ..RunConfig::default()
    };
    (dir, config)
}

#[test]
fn the_proposal_finds_the_pane_from_the_sparse_points() {
    let config = SyntheticConfig { sparse_points: 4000, ..SyntheticConfig::small() };
    let (found, truth) = proposed(&config);
    assert_eq!(truth.len(), 1, "the scene has one pane");
    let pane = truth[0];
    assert_eq!(found.len(), 1, "one candidate: {found:#?}");
    let plane = found[0].plane.expect("a plane over the see-through region");
    let angle = plane.unit_normal().dot(pane.unit_normal()).clamp(-1.0, 1.0).acos().to_degrees();
    assert!(
        angle < 2.0,
        "normal {angle:.2} degrees off, facing the cameras: {plane:?} vs {pane:?}"
    );
    let size = pane.width.max(pane.height);
    let off = plane.centre.distance(pane.centre) / size;
    assert!(off < 0.1, "centre {:.1}% of the pane's size away: {plane:?} vs {pane:?}", 100.0 * off);
}

#[test]
fn the_closed_room_gets_no_candidate() {
    let config =
        SyntheticConfig { sparse_points: 4000, ..SyntheticConfig::small() }.without_glass();
    let (found, truth) = proposed(&config);
    assert!(truth.is_empty());
    assert!(found.is_empty(), "{found:#?}");
}

#[test]
fn an_auto_run_proposes_tries_and_decides() {
    let (_dir, config) = auto_run("planes-auto", 4000, None);
    let out = config.out.clone();
    let mut run = TrainingRun::start(config, RunOptions::default()).expect("a run");
    let mut lines = Vec::new();
    let mut created = 0;
    run.run_to_end(|e| match e {
        RunEvent::Note(line) if line.contains("candidate plane") => lines.push(line.clone()),
        RunEvent::PlaneCreated { .. } => created += 1,
        _ => {}
    })
    .expect("the run finishes");
    assert_eq!(created, 0, "no plane comes from the masks, which auto ignores");
    assert!(lines.iter().any(|l| l.contains("on trial")), "{lines:#?}");
    assert!(
        lines.iter().any(|l| l.contains(": kept: ") || l.contains(": dropped: ")),
        "{lines:#?}"
    );
    let metrics = std::fs::read_to_string(out.join("metrics.json")).expect("metrics.json");
    let metrics: serde_json::Value = serde_json::from_str(&metrics).expect("JSON");
    let candidates = metrics["candidates"].as_array().expect("the candidates");
    let tried: Vec<_> = candidates.iter().filter(|c| c["proposed"] == true).collect();
    assert!(!tried.is_empty(), "{candidates:#?}");
    assert!(tried.iter().all(|c| c["held_out_l1_gain"].is_number() && c["strength"].is_number()));
    let kept = tried.iter().filter(|c| c["kept"] == true).count();
    assert_eq!(metrics["planes"].as_u64(), Some(kept as u64), "the run ends with the kept planes");
}

#[test]
fn a_proposal_without_evidence_is_tried_again_then_given_up() {
    // Too few sparse points to show the pane, and no densification within the run to grow the
    // model: every try waits or finds nothing, each says when the next comes, the last gives up.
    let (_dir, config) = auto_run("planes-auto-retry", 40, None);
    let out = config.out.clone();
    let mut run = TrainingRun::start(config, RunOptions::default()).expect("a run");
    let mut lines = Vec::new();
    run.run_to_end(|e| {
        if let RunEvent::Note(line) = e
            && (line.starts_with("no proposal") || line.starts_with("no candidate plane"))
        {
            lines.push(line.clone());
        }
    })
    .expect("the run finishes");
    // Stage 1 is 4 of 40 steps: tries at 4, 8, ..., 20 (half the run); the model is not
    // grown by then (no densification before step 100), so all but the last wait.
    assert_eq!(lines.len(), 5, "{lines:#?}");
    for (k, line) in lines[..4].iter().enumerate() {
        let (at, next) = (4 * (k + 1), 4 * (k + 2));
        assert!(line.starts_with(&format!("no proposal at step {at}: ")), "{line}");
        assert!(line.ends_with(&format!("trying again at step {next}")), "{line}");
    }
    let last = &lines[4];
    assert!(last.starts_with("no candidate plane at step 20 "), "{last}");
    assert!(last.ends_with("training plain 3DGS"), "{last}");
    let metrics = std::fs::read_to_string(out.join("metrics.json")).expect("metrics.json");
    let metrics: serde_json::Value = serde_json::from_str(&metrics).expect("JSON");
    assert_eq!(metrics["planes"].as_u64(), Some(0));
    let candidates = metrics["candidates"].as_array().expect("the last try's candidates");
    assert!(candidates.iter().all(|c| c["proposed"] == false), "{candidates:#?}");
}

#[test]
fn a_later_proposal_ends_stage1_there_and_a_resume_keeps_it() {
    // 4000 sparse points and no densification within 40 steps: the model never reaches twice
    // that, so the proposal waits to its last try (step 20), which proposes the pane.
    let (_dir, config) = auto_run("planes-auto-late", 4000, Some(5));
    let out = config.out.clone();
    let mut run = TrainingRun::start(config, RunOptions::default()).expect("a run");
    let mut moved = Vec::new();
    loop {
        match run.next_event().expect("the run goes on").expect("a step") {
            RunEvent::Note(line) if line.starts_with("stage 1 ends") => moved.push(line),
            RunEvent::CheckpointWritten { step, .. } if step >= 25 => break,
            _ => {}
        }
    }
    assert_eq!(moved, ["stage 1 ends at step 20, where the proposal found its candidates"]);
    assert_eq!(run.trainer().settings.stage1, 20);
    drop(run);
    let resumed = TrainingRun::resume(&out, RunOptions::default()).expect("resume");
    assert_eq!(resumed.trainer().settings.stage1, 20, "the checkpoint keeps where stage 1 ended");
    assert_eq!(resumed.trainer().settings.stage2, 4, "stage 2 keeps its length");
}
