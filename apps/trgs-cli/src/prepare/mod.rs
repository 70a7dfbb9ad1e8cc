//! `prepare`: photos or a video's frames in, a scene folder out (`images/` and `sparse/0/`),
//! through COLMAP's command-line program, as INRIA's `convert.py` and nerfstudio's
//! `ns-process-data` do: the photos are checked and turned upright ([`photos`]), COLMAP extracts
//! features, matches them (every pair for photos, neighbours in order for a video's frames) and
//! maps ([`colmap`]), and the largest model is kept ([`model`]). Undistortion is left to trgs,
//! which reads COLMAP's lens models.
//!
//! The `colmap` program (Debian's and most distributions' `colmap` package, or a build of its
//! own) rather than PyPI's pycolmap: a command that runs a program needs no Python, and the
//! program's flags are the ones users know from COLMAP's own documentation and recipes.
pub mod colmap;
pub mod model;
pub mod photos;

use anyhow::{Context, Result, bail};
use std::path::PathBuf;
use std::time::Instant;

/// How COLMAP pairs images to match.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Matching {
    /// Every pair: photos taken in any order (quadratic in their number)
    Exhaustive,
    /// Each frame with its neighbours in file-name order: a video's frames
    Sequential,
}

/// What to prepare and how.
#[derive(Clone, Debug)]
pub struct PrepareOptions {
    /// The folder of photos or frames (JPEG or PNG).
    pub input: PathBuf,
    /// The scene folder to write.
    pub out: PathBuf,
    pub matching: Matching,
    /// Keep every n-th image, in file-name order.
    pub every: usize,
    /// COLMAP's camera model (one camera for all photos when they share one size).
    pub camera_model: String,
    /// Keep the focal length of the first estimate: short baselines (a video panning along a
    /// facade) give COLMAP too little parallax to refine it.
    pub fix_focal: bool,
    /// The `colmap` program.
    pub colmap: PathBuf,
    /// CPU threads for COLMAP (-1: all).
    pub threads: i32,
}

/// What `prepare` made.
#[derive(Clone, Debug)]
pub struct Prepared {
    pub images: usize,
    pub registered: usize,
    pub points: usize,
    /// The other models COLMAP split the images into, by their image counts (dropped).
    pub dropped_models: Vec<usize>,
}

/// Run every stage, printing a line as each starts and ends.
pub fn prepare(options: &PrepareOptions, say: &mut dyn FnMut(String)) -> Result<Prepared> {
    let program = colmap::Colmap::find(&options.colmap, options.threads)?;
    let out = &options.out;
    if out.join("images").exists() || out.join("sparse").exists() {
        bail!(
            "{} already holds images/ or sparse/: prepare writes a new scene folder; choose \
             another --out or remove them",
            out.display()
        );
    }
    let t0 = Instant::now();
    let chosen = photos::gather(&options.input, options.every)?;
    say(format!(
        "photos: {} of {} images in {} (every {})",
        chosen.kept.len(),
        chosen.found,
        options.input.display(),
        options.every
    ));
    let images = out.join("images");
    let sizes = photos::write_upright(&chosen.kept, &images, say)?;
    let copied = sizes.len();
    // One camera shared by every photo constrains COLMAP best, but a camera has one size: photos
    // of several sizes (a phone's portrait and landscape shots) get a camera each, or COLMAP
    // registers only those of the first one's size.
    let single_camera = sizes.windows(2).all(|w| w[0] == w[1]);
    if !single_camera {
        let portrait = sizes.iter().filter(|(w, h)| h > w).count();
        say(format!(
            "photos: of several sizes ({portrait} portrait, {} landscape or square): a camera for \
             each photo",
            copied - portrait
        ));
    }
    say(format!("photos: checked and written to {} ({:.0} s)", images.display(), secs(t0)));
    let work = out.join("colmap");
    std::fs::create_dir_all(&work).with_context(|| format!("creating {}", work.display()))?;
    let database = work.join("database.db");
    let stage = |name: &str, say: &mut dyn FnMut(String), run: &dyn Fn() -> Result<()>| {
        let t = Instant::now();
        say(format!("colmap: {name} ..."));
        run()?;
        say(format!("colmap: {name} done ({:.0} s)", secs(t)));
        Ok::<(), anyhow::Error>(())
    };
    stage("feature extraction", say, &|| {
        program.extract_features(&database, &images, &options.camera_model, single_camera)
    })?;
    let matcher = match options.matching {
        Matching::Exhaustive => "exhaustive matching",
        Matching::Sequential => "sequential matching",
    };
    stage(matcher, say, &|| program.match_features(&database, options.matching))?;
    let target = out.join("sparse").join("0");
    let map = |init_angle: Option<f64>, say: &mut dyn FnMut(String)| {
        let models = match init_angle {
            None => work.join("sparse"),
            Some(angle) => work.join(format!("sparse-from-{angle}deg")),
        };
        let mapped = stage("mapping", say, &|| {
            program.map(&database, &images, &models, options.fix_focal, init_angle)
        });
        // The mapper fails when it finds no pair to start from: that is no model, said as such.
        let kept = model::keep_largest(&models, &target, copied);
        match (mapped, kept) {
            (Err(e), Err(none)) => Err(e.context(none.to_string())),
            (Err(e), Ok(_)) => Err(e),
            (Ok(()), kept) => kept,
        }
    };
    let mut kept = map(None, say);
    // A capture that only pans: start from pairs seen at ever smaller angles.
    let mut said_before = String::new();
    for angle in colmap::RETRY_INIT_ANGLES {
        let Err(failed) = &kept else { break };
        let why = failed.to_string();
        let said = if why == said_before { "the same again" } else { why.as_str() };
        say(format!(
            "colmap: {said}; mapping again from a pair seen at {angle}° or more (a short-baseline \
             capture)"
        ));
        said_before = why;
        kept = map(Some(angle), say);
    }
    let kept = kept.with_context(|| {
        let angles: Vec<String> =
            colmap::RETRY_INIT_ANGLES.iter().map(|a| format!("{a}°")).collect();
        format!(
            "mapping failed from COLMAP's default initial pair and from pairs seen at {}{}",
            angles.join(", "),
            if options.fix_focal { "" } else { "; for a video that only pans try --fix-focal" }
        )
    })?;
    for line in kept.notes() {
        say(line);
    }
    say(format!(
        "scene folder {} written ({:.0} s): train --data {}",
        out.display(),
        secs(t0),
        out.display()
    ));
    Ok(Prepared {
        images: copied,
        registered: kept.registered,
        points: kept.points,
        dropped_models: kept.dropped,
    })
}

fn secs(t: Instant) -> f64 {
    t.elapsed().as_secs_f64()
}
