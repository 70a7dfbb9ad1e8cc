//! Planes without masks: the proposal finds the synthetic scene's pane from its sparse points
//! and cameras alone and proposes nothing in the closed room; a `--planes auto` run proposes,
//! tries and decides its candidates, and says so in its events, log and metrics.
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
    let dir = ScratchDir::new("planes-auto");
    let data = dir.join("data");
    let config = SyntheticConfig { sparse_points: 4000, ..SyntheticConfig::small() };
    write_dataset(&generate(&config), &data).expect("dataset");
    let out = dir.join("run");
    let config = RunConfig {
        data: Some(data),
        out: out.clone(),
        iterations: 40,
        sh_degree: 1,
        planes: Some(PlaneSource::Auto),
        ..RunConfig::default()
    };
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
