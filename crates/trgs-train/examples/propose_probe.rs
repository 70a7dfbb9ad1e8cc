//! Probe: the plane proposal on a scene folder's sparse points and a model's opaque primary
//! Gaussians, seen by its training views, as `--planes auto` runs it at the end of stage 1.
//! `cargo run --release --example propose_probe -p trgs-train -- SCENE [MODEL.ply|checkpoint.trgs]`
//! A checkpoint is the model at the step it was written: a run with `--checkpoint-every 200`
//! holds the model each proposal try sees (copy the file away after each step you want).
//! For a synthetic scene (a `gt/planes.json` beside its images) each proposed plane is also
//! measured against the nearest true one: the first rectangle the trial starts from.
//! `--seed S` (after the model) seeds RANSAC with S instead of 1; `--seeds N` runs the proposal
//! with RANSAC seeds 1..=N instead and prints one line per seed: each true plane's nearest
//! proposed plane against it. The first rectangle depends on which structures RANSAC draws,
//! and a run's draws are not the probe's.
use glam::DVec3;
use std::path::Path;
use trgs_core::fit::{ProposalSettings, propose_planes};
use trgs_core::io::ply::read_ply;
use trgs_core::io::{SceneFolder, read_planes_json};
use trgs_core::rng::Rng;
use trgs_core::scene::{Camera, ReflectionPlane};
use trgs_train::checkpoint::read_checkpoint;
use trgs_train::run::opaque_centres;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let Some(scene) = args.get(1).map(Path::new) else {
        eprintln!("usage: propose_probe SCENE [MODEL.ply|checkpoint.trgs]");
        std::process::exit(2);
    };
    let folder = SceneFolder::open(scene)?;
    // As the trial: the model's opaque primary centres, then the sparse points.
    let mut points = match args.get(2).map(Path::new) {
        Some(model) if model.extension().is_some_and(|e| e == "trgs") => {
            let ck = read_checkpoint(model)?;
            println!("checkpoint of step {}", ck.step);
            opaque_centres(&ck.state.gaussians)
        }
        Some(model) => opaque_centres(&read_ply(model)?),
        None => Vec::new(),
    };
    let sparse = folder.points.len();
    points.extend(folder.points.iter().map(|(p, _)| DVec3::from_array(*p)));
    let cameras: Vec<_> = folder
        .views
        .iter()
        .filter(|v| !folder.test_views.contains(&v.camera.name))
        .map(|v| v.camera.clone())
        .collect();
    let centre = points.iter().copied().sum::<DVec3>() / points.len() as f64;
    let cam_centre = cameras.iter().map(|c| c.pose.centre()).sum::<DVec3>() / cameras.len() as f64;
    let extent =
        cameras.iter().map(|c| c.pose.centre().distance(cam_centre)).fold(0.0, f64::max) * 1.1;
    println!(
        "{} points ({sparse} sparse), {} cameras, extent {extent:.3}, centre {centre:.3}",
        points.len(),
        cameras.len()
    );
    let truth_path = scene.join("gt").join("planes.json");
    let truths: Vec<ReflectionPlane> = if truth_path.is_file() {
        read_planes_json(&truth_path)?.into_iter().filter_map(|s| s.plane).collect()
    } else {
        Vec::new()
    };
    if let Some(n) = args.iter().position(|a| a == "--seeds").and_then(|i| args.get(i + 1)) {
        seed_sweep(&points, &cameras, &truths, n.parse()?);
        return Ok(());
    }
    let seed = match args.iter().position(|a| a == "--seed").and_then(|i| args.get(i + 1)) {
        Some(s) => s.parse()?,
        None => 1,
    };
    let t = std::time::Instant::now();
    let found =
        propose_planes(&points, &cameras, &ProposalSettings::default(), &mut Rng::new(seed));
    println!("proposal took {:.2} s, scale {:.3}", t.elapsed().as_secs_f64(), found.scale);
    for c in &found.candidates {
        let p = c.plane.map(|p| {
            format!(
                "n {:.3} c {:.3} axis {:.3} {:.2}x{:.2}",
                p.unit_normal(),
                p.centre,
                p.axis,
                p.width,
                p.height
            )
        });
        println!(
            "support {:6} seen {:6} ({:5.1}%) front {:4.2} flat {:.2} ({:.2} over its own cells) size {:.2}x{:.2} {:?} opening of {:?} -> {}",
            c.support,
            c.seen_through,
            100.0 * c.seen_fraction,
            c.cameras_in_front,
            c.planarity,
            c.wall_planarity,
            c.structure_size.0,
            c.structure_size.1,
            p,
            c.opening_of,
            c.rejected.clone().unwrap_or("PROPOSED".into())
        );
    }
    // A synthetic scene's truth: each proposed plane against the nearest true one, measured as
    // `train` measures its planes (normal angle, centre distance over the true diagonal), with
    // its extent along the true plane's axes.
    for (k, c) in found.candidates.iter().enumerate() {
        let (None, Some(p)) = (&c.rejected, c.plane) else { continue };
        let nearest = truths.iter().min_by(|a, b| {
            let d = |t: &&ReflectionPlane| p.centre.distance(t.centre);
            d(a).total_cmp(&d(b))
        });
        if let Some(t) = nearest {
            let (a, b) = (t.axis.normalize(), t.unit_normal().cross(t.axis.normalize()));
            let (u, v) = (p.axis.normalize(), p.unit_normal().cross(p.axis.normalize()));
            let along = |e: DVec3| u.dot(e).abs() * p.width + v.dot(e).abs() * p.height;
            let (angle, centre) = p.error_against(t);
            println!(
                "candidate {k} against the truth: normal off by {angle:.2} deg, centre by \
                 {:.2}% of the size, {:.2} x {:.2} along its axes (truth {:.2} x {:.2})",
                100.0 * centre,
                along(a),
                along(b),
                t.width,
                t.height
            );
        }
    }
    Ok(())
}

/// The proposal with seeds 1..=`seeds`: per seed, the proposed count and each true plane's
/// nearest proposed plane (normal and centre error, size), or "none".
fn seed_sweep(points: &[DVec3], cameras: &[Camera], truths: &[ReflectionPlane], seeds: u64) {
    let mut within = vec![0usize; truths.len()];
    for seed in 1..=seeds {
        let found =
            propose_planes(points, cameras, &ProposalSettings::default(), &mut Rng::new(seed));
        let proposed: Vec<ReflectionPlane> = found
            .candidates
            .iter()
            .filter(|c| c.rejected.is_none())
            .filter_map(|c| c.plane)
            .collect();
        let mut line = format!("seed {seed:3}: {} proposed", proposed.len());
        for (k, t) in truths.iter().enumerate() {
            let nearest = proposed
                .iter()
                .min_by(|a, b| a.centre.distance(t.centre).total_cmp(&b.centre.distance(t.centre)));
            match nearest {
                Some(p) => {
                    let (angle, centre) = p.error_against(t);
                    within[k] += usize::from(angle <= 2.0 && centre <= 0.02);
                    line += &format!(
                        "; truth {k}: {angle:.2} deg, {:.2}%, {:.2} x {:.2}",
                        100.0 * centre,
                        p.width,
                        p.height
                    );
                }
                None => line += &format!("; truth {k}: none"),
            }
        }
        println!("{line}");
    }
    for (k, n) in within.iter().enumerate() {
        println!("truth {k}: within 2 deg and 2% in {n} of {seeds} seeds");
    }
}
