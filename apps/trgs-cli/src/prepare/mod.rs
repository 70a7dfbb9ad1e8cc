//! `prepare`: photos or a video's frames in, a scene folder out (`images/` and `sparse/0/`),
//! through COLMAP's command-line program, as INRIA's `convert.py` and nerfstudio's
//! `ns-process-data` do: the photos are checked and turned upright ([`photos`]), COLMAP extracts
//! features, matches them (every pair for photos, neighbours in order for a video's frames) and
//! maps ([`colmap`]), and the largest model is kept ([`model`]). Undistortion is left to trgs,
//! which reads COLMAP's lens models. A run stopped or failed halfway is picked up by the next
//! one into the same folder ([`progress`]): the photos and features are not redone unless the
//! flags they depend on changed, so a retry with another `--matching` costs only the matching.
//!
//! The `colmap` program (Debian's and most distributions' `colmap` package, or a build of its
//! own) rather than PyPI's pycolmap: a command that runs a program needs no Python, and the
//! program's flags are the ones users know from COLMAP's own documentation and recipes.
pub mod colmap;
pub mod model;
pub mod photos;
pub mod progress;

use anyhow::{Context, Result, bail};
use progress::Progress;
use std::path::{Path, PathBuf};
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
    /// Keep the largest model when COLMAP splits the images into several (else an error).
    pub keep_largest: bool,
    /// Keep the focal length COLMAP starts from (the EXIF one, or its guess of 1.2 x the larger
    /// side): short baselines (a video panning along a facade) give it too little parallax to
    /// refine it.
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
    let out = &options.out;
    let work = out.join("colmap");
    let images = out.join("images");
    let target = out.join("sparse").join("0");
    refuse_input_inside(&options.input, out)?;
    // COLMAP maps with models trgs cannot undistort (FOV, THIN_PRISM_FISHEYE): refused before
    // its hour of mapping, not by `train` after it.
    if !trgs_core::lens::READ_MODELS.contains(&options.camera_model.as_str()) {
        bail!(
            "--camera-model {}: trgs reads only {}",
            options.camera_model,
            trgs_core::lens::read_models_list()
        );
    }
    if target.exists() {
        bail!(
            "{} is already a scene folder (it holds sparse/0): choose another --out, or remove \
             its images/, sparse/ and colmap/ to prepare it again",
            out.display()
        );
    }
    let program = colmap::Colmap::find(&options.colmap, options.threads)?.logging_to(&work);
    // The input is checked before anything is written: a refused run leaves no folder behind.
    let chosen = photos::gather(&options.input, options.every)?;
    if options.matching == Matching::Sequential && !photos::names_sort_as_numbered(&chosen.kept) {
        bail!(
            "{}: the frames are numbered without zero padding (frame_10 sorts before frame_2 as \
             text), and COLMAP's sequential matching pairs them in text order: rename them with \
             padded numbers (ffmpeg: frame_%04d.jpg) or use --matching exhaustive",
            options.input.display()
        );
    }
    let mut progress = open_progress(out, &work, &images, say)?;
    say(format!("colmap: {}", program.version()));
    let t0 = Instant::now();
    say(format!(
        "photos: {} of {} images in {} (every {})",
        chosen.kept.len(),
        chosen.found,
        options.input.display(),
        options.every
    ));
    let photos_key = photos::fingerprint(&options.input, options.every, &chosen.kept)?;
    let sizes = if progress.is_done("photos", &photos_key) && images.is_dir() {
        say("photos: written by the earlier run".to_string());
        photos::sizes_in(&chosen.kept, &images)?
    } else {
        progress.forget_from("photos")?;
        if images.exists() {
            std::fs::remove_dir_all(&images)
                .with_context(|| format!("clearing {} of the earlier run", images.display()))?;
        }
        let sizes = photos::write_upright(&chosen.kept, &images, say)?;
        progress.record("photos", &photos_key)?;
        say(format!("photos: checked and written to {} ({:.0} s)", images.display(), secs(t0)));
        sizes
    };
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
    let database =
        extract_and_match(options, &program, &mut progress, &photos_key, single_camera, say)?;
    let picked = map_with_retries(options, &program, &database, copied, say)?;
    if !options.keep_largest {
        picked.refuse_split()?;
    }
    let kept = picked.write(&target)?;
    for line in kept.notes() {
        say(line);
    }
    // The matched database stays for COLMAP's own tools; the features-only copy was for reruns.
    remove_if_present(&work.join("features.db"))?;
    say(format!(
        "scene folder {} written ({:.0} s): trgs train --data {}",
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

/// The progress of an unfinished run into `out`, or a new one; folders there that no run of
/// prepare wrote are refused.
fn open_progress(
    out: &Path,
    work: &Path,
    images: &Path,
    say: &mut dyn FnMut(String),
) -> Result<Progress> {
    Ok(match Progress::load(work)? {
        Some(p) => {
            say(format!(
                "{}: resuming the unfinished prepare there (stages whose flags did not change \
                 are kept)",
                out.display()
            ));
            p
        }
        None if images.exists() || out.join("sparse").exists() || work.exists() => bail!(
            "{} already holds images/, sparse/ or colmap/ that prepare did not write: choose \
             another --out or remove them",
            out.display()
        ),
        None => Progress::start(work)?,
    })
}

/// Run one COLMAP stage, saying when it starts and how long it took.
fn stage(name: &str, say: &mut dyn FnMut(String), run: &dyn Fn() -> Result<()>) -> Result<()> {
    let t = Instant::now();
    say(format!("colmap: {name} ..."));
    run()?;
    say(format!("colmap: {name} done ({:.0} s)", secs(t)));
    Ok(())
}

/// Extract features and match them (each stage kept from an earlier run whose inputs were the
/// same); returns the matched database.
fn extract_and_match(
    options: &PrepareOptions,
    program: &colmap::Colmap,
    progress: &mut Progress,
    photos_key: &str,
    single_camera: bool,
    say: &mut dyn FnMut(String),
) -> Result<PathBuf> {
    let work = options.out.join("colmap");
    let images = options.out.join("images");
    let features = work.join("features.db");
    let database = work.join("database.db");
    let features_key =
        key(&[photos_key, &options.camera_model, &format!("single camera {single_camera}")]);
    if progress.is_done("features", &features_key) && features.is_file() {
        say("colmap: feature extraction done by the earlier run".to_string());
    } else {
        progress.forget_from("features")?;
        remove_if_present(&features)?;
        stage("feature extraction", say, &|| {
            program.extract_features(&features, &images, &options.camera_model, single_camera)
        })?;
        progress.record("features", &features_key)?;
    }
    let matcher = match options.matching {
        Matching::Exhaustive => "exhaustive matching",
        Matching::Sequential => "sequential matching",
    };
    let matching_key = key(&[&features_key, matcher]);
    if progress.is_done("matching", &matching_key) && database.is_file() {
        say(format!("colmap: {matcher} done by the earlier run"));
    } else {
        progress.forget_from("matching")?;
        // Matching starts from the features alone: matches of another --matching would stay in
        // the database and join the mapping.
        copy_atomic(&features, &database)?;
        stage(matcher, say, &|| program.match_features(&database, options.matching))?;
        progress.record("matching", &matching_key)?;
    }
    Ok(database)
}

/// Map from COLMAP's default initial pair, then, for a capture that only pans, from pairs seen
/// at ever smaller angles; the largest model of the first mapping that registers enough.
fn map_with_retries(
    options: &PrepareOptions,
    program: &colmap::Colmap,
    database: &Path,
    copied: usize,
    say: &mut dyn FnMut(String),
) -> Result<model::Picked> {
    let work = options.out.join("colmap");
    let images = options.out.join("images");
    clear_models(&work)?;
    let map = |init_angle: Option<f64>, say: &mut dyn FnMut(String)| {
        let models = match init_angle {
            None => work.join("sparse"),
            Some(angle) => work.join(format!("sparse-from-{angle}deg")),
        };
        let mapped = stage("mapping", say, &|| {
            program.map(database, &images, &models, options.fix_focal, init_angle)
        });
        // The mapper fails when it finds no pair to start from: that is no model, said as such.
        // A failed mapping keeps nothing, whatever models it left.
        let picked = model::pick_largest(&models, copied, options.matching);
        match (mapped, picked) {
            (Err(e), Err(none)) => Err(e.context(none.to_string())),
            (Err(e), Ok(_)) => Err(e),
            (Ok(()), picked) => picked,
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
    kept.with_context(|| {
        let angles: Vec<String> =
            colmap::RETRY_INIT_ANGLES.iter().map(|a| format!("{a}°")).collect();
        format!(
            "mapping failed from COLMAP's default initial pair and from pairs seen at {}{} \
             (COLMAP's output: {}; a rerun into the same --out keeps the photos and features)",
            angles.join(", "),
            if options.fix_focal { "" } else { "; for a video that only pans try --fix-focal" },
            work.display()
        )
    })
}

/// A progress key of `parts` (one line: tabs and line breaks would break the file's format).
fn key(parts: &[&str]) -> String {
    parts.join(" | ").replace(['\t', '\n', '\r'], " ")
}

/// The photos must not be where `prepare` writes: clearing an unfinished run's images/ would
/// delete them (the INRIA layout keeps a capture's photos in `SCENE/images`). Photos in `SCENE`
/// itself or in `SCENE/input` (`convert.py`'s layout) are fine.
fn refuse_input_inside(input: &Path, out: &Path) -> Result<()> {
    let canonical = |p: &Path| std::fs::canonicalize(p).ok();
    let Some(input) = canonical(input) else { return Ok(()) };
    for written in ["images", "sparse", "colmap"] {
        let Some(place) = canonical(&out.join(written)) else { continue };
        if input.starts_with(&place) {
            bail!(
                "the photos ({}) are in {}, which prepare writes: move them elsewhere (for \
                 instance to {}) or choose another --out",
                input.display(),
                place.display(),
                out.join("input").display()
            );
        }
    }
    Ok(())
}

fn remove_if_present(path: &Path) -> Result<()> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            Err(e).with_context(|| format!("removing {}", path.display()))
        }
        _ => Ok(()),
    }
}

/// Copy `from` to a temporary name beside `to`, then rename it into place.
fn copy_atomic(from: &Path, to: &Path) -> Result<()> {
    let partial = to.with_extension("partial");
    std::fs::copy(from, &partial)
        .with_context(|| format!("copying {} to {}", from.display(), partial.display()))?;
    std::fs::rename(&partial, to)
        .with_context(|| format!("renaming {} to {}", partial.display(), to.display()))
}

/// Remove the models of an earlier mapping (`sparse/`, `sparse-from-*deg/`): the largest is
/// picked among the folders there, which must all come from this run's matches.
fn clear_models(work: &Path) -> Result<()> {
    let entries = std::fs::read_dir(work).with_context(|| format!("listing {}", work.display()))?;
    for e in entries {
        let path = e.with_context(|| format!("listing {}", work.display()))?.path();
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        if path.is_dir() && (name == "sparse" || name.starts_with("sparse-from-")) {
            std::fs::remove_dir_all(&path)
                .with_context(|| format!("removing {}", path.display()))?;
        }
    }
    Ok(())
}

fn secs(t: Instant) -> f64 {
    t.elapsed().as_secs_f64()
}
