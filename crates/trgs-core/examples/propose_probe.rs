//! Probe: the plane proposal on a scene folder's sparse points (and a model's opaque Gaussians).
//! `cargo run --example propose_probe -p trgs-core -- SCENE [MODEL.ply]`
use glam::DVec3;
use std::path::Path;
use trgs_core::fit::{ProposalSettings, propose_planes};
use trgs_core::io::SceneFolder;
use trgs_core::rng::Rng;
use trgs_core::scene::Population;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let folder = SceneFolder::open(Path::new(&args[1])).expect("scene");
    let mut points: Vec<DVec3> = folder.points.iter().map(|(p, _)| DVec3::from_array(*p)).collect();
    let sparse = points.len();
    if let Some(model) = args.get(2) {
        let g = trgs_core::io::ply::read_ply(Path::new(model)).expect("ply");
        for i in 0..g.len() {
            let o = 1.0 / (1.0 + (-g.opacity_logits[i]).exp());
            if o > 0.5 && g.populations[i] == Population::Primary {
                points.push(DVec3::from_array(g.means[i].map(f64::from)));
            }
        }
    }
    let cameras: Vec<_> = folder.views.iter().map(|v| v.camera.clone()).collect();
    let centre = points.iter().copied().sum::<DVec3>() / points.len() as f64;
    let cam_centre = cameras.iter().map(|c| c.pose.centre()).sum::<DVec3>() / cameras.len() as f64;
    let extent =
        cameras.iter().map(|c| c.pose.centre().distance(cam_centre)).fold(0.0, f64::max) * 1.1;
    println!(
        "{} points ({sparse} sparse), {} cameras, extent {extent:.3}, centre {centre:.3}",
        points.len(),
        cameras.len()
    );
    let t = std::time::Instant::now();
    let found = propose_planes(&points, &cameras, &ProposalSettings::default(), &mut Rng::new(1));
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
}
