//! `bench --host`: the CPU's work around the GPU's in a run at scale, which a GPU waits for:
//! loading a 12 MP photo (decode, then the area downscale to 1600x1200), the SSIM of a test view
//! at 1600x1200 (each evaluation computes one per test view), and writing and reading a
//! checkpoint and a model.ply of a million Gaussians (SH degree 3). Medians over `reps`.
use anyhow::{Context, Result};
use std::time::Instant;
use trgs_core::Image;
use trgs_core::fixtures::{RoomDensity, RoomSpec, room_scene};
use trgs_core::scene::{PerAttribute, attribute_widths};
use trgs_train::checkpoint::{Checkpoint, read_checkpoint, write_checkpoint};
use trgs_train::stages::TrainState;

/// One measured piece of work.
struct Timed {
    work: &'static str,
    size: String,
    ms: f64,
}

/// The median milliseconds of `reps` calls of `work`, and its last result.
fn timed<T>(reps: usize, mut work: impl FnMut() -> Result<T>) -> Result<(f64, T)> {
    let mut times = Vec::with_capacity(reps);
    let mut last = None;
    for _ in 0..reps.max(1) {
        let t = Instant::now();
        let out = work()?;
        times.push(t.elapsed().as_secs_f64() * 1e3);
        // Dropped after the clock stops: freeing the last result is not part of the work.
        last = Some(out);
    }
    #[allow(clippy::expect_used)]
    Ok((super::common::median(times), last.expect("at least one rep")))
}

/// A photo-like image: smooth shading with edges, so that JPEG has detail to code.
fn photo(width: u32, height: u32) -> Image<f32> {
    let mut im = Image::<f32>::new(width, height, 3);
    for (i, px) in im.data.chunks_exact_mut(3).enumerate() {
        let (x, y) = ((i as u32 % width) as f32, (i as u32 / width) as f32);
        let check = if (x as u32 / 37 + y as u32 / 53).is_multiple_of(2) { 0.05 } else { -0.05 };
        for (c, v) in px.iter_mut().enumerate() {
            let shade = (x * 0.013 + c as f32).sin() * (y * 0.007).cos();
            *v = (0.5 + 0.4 * shade + check).clamp(0.0, 1.0);
        }
    }
    im
}

pub fn bench_host(reps: usize) -> Result<()> {
    let dir = trgs_core::scratch::ScratchDir::new("bench-host");
    let mut rows = Vec::new();

    let jpeg = dir.join("photo.jpg");
    trgs_core::io::png::write_jpeg_rgb(&jpeg, &photo(4000, 3000), 92)?;
    let (ms, decoded) = timed(reps, || Ok(trgs_core::io::png::read_rgb8_image(&jpeg)?))?;
    rows.push(Timed { work: "decode a JPEG photo", size: "4000x3000".into(), ms });
    let (ms, view) =
        timed(reps, || Ok(trgs_train::resize_area_u8(&decoded, 1600, 1200).quantised()))?;
    rows.push(Timed {
        work: "downscale it (area filter, to 8 bits)",
        size: "to 1600x1200".into(),
        ms,
    });

    let (a, b) = (view.to_f32(), trgs_train::resize_area_u8(&decoded, 1600, 1200));
    let (ms, _) = timed(reps, || Ok(trgs_core::metrics::ssim(&a, &b)?))?;
    rows.push(Timed { work: "SSIM of a test view", size: "1600x1200".into(), ms });

    let n = 1_000_000;
    let spec = RoomSpec {
        seed: 7,
        gaussians: n,
        planes: 1,
        width: 1600,
        height: 1200,
        sh_degree: 3,
        density: RoomDensity::AsCaptured,
    };
    let scene = room_scene(&spec);
    let gaussians = scene.gaussians.cast::<f32>();
    let widths = attribute_widths(gaussians.sh_coeffs());
    let moments = PerAttribute::from_fn(|a| vec![1e-3f32; gaussians.len() * widths[a]]);
    let ck = Checkpoint {
        step: 1,
        state: TrainState { gaussians, m: moments.clone(), v: moments },
        planes: scene.planes,
        plane_moments: vec![Default::default()],
        exposures: Default::default(),
        densify_stats: None,
        rng_state: 1,
        extra: serde_json::Value::Null,
    };
    let count = ck.state.gaussians.len();
    let path = dir.join(trgs_train::checkpoint::CHECKPOINT_FILE);
    let (ms, ()) = timed(reps, || Ok(write_checkpoint(&path, &ck)?))?;
    let bytes = std::fs::metadata(&path).context("the checkpoint written")?.len();
    let size = format!("{count} Gaussians, {}", trgs_train::human_bytes(bytes));
    rows.push(Timed { work: "write a checkpoint (synced)", size: size.clone(), ms });
    let (ms, _) = timed(reps, || Ok(read_checkpoint(&path)?))?;
    rows.push(Timed { work: "read it", size, ms });

    let ply = dir.join("model.ply");
    let (ms, ()) = timed(reps, || Ok(trgs_core::io::write_ply(&ply, &ck.state.gaussians)?))?;
    let bytes = std::fs::metadata(&ply).context("the model written")?.len();
    let size = format!("{count} Gaussians, {}", trgs_train::human_bytes(bytes));
    rows.push(Timed { work: "write model.ply (synced)", size: size.clone(), ms });
    let (ms, _) = timed(reps, || Ok(trgs_core::io::read_ply(&ply)?))?;
    rows.push(Timed { work: "read it", size, ms });

    println!("\n| work | size | ms |\n|---|---|---:|");
    for r in &rows {
        println!("| {} | {} | {:.0} |", r.work, r.size, r.ms);
    }
    Ok(())
}
