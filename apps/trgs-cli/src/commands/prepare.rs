//! `prepare`: a folder of photos or a video's frames to a scene folder `train` reads, through
//! COLMAP ([`crate::prepare`]).
use crate::prepare::{Matching, PrepareOptions, prepare};
use anyhow::Result;
use clap::Parser;
use std::path::PathBuf;

/// A scene folder from photos: COLMAP's features, matches and mapping (the `colmap` program),
/// the largest model kept as sparse/0, the photos checked and turned upright into images/.
///
/// Photos taken around a room or an object: the default exhaustive matching. A video's frames
/// (named in order, numbers zero-padded): --matching sequential, with --every to thin them.
/// A run that failed or was stopped is picked up by running it again with the same --out: the
/// photos and features are kept unless the flags they depend on changed.
#[derive(Debug, Parser)]
#[command(name = "prepare", version, after_help = "Then: trgs train --data OUT")]
pub struct Args {
    /// The folder of photos or frames (JPEG or PNG)
    input: PathBuf,
    /// The scene folder to write (images/, sparse/0/, and COLMAP's database in colmap/)
    #[arg(long)]
    out: PathBuf,
    /// How COLMAP pairs images to match
    #[arg(long, value_enum, default_value = "exhaustive")]
    matching: Matching,
    /// Keep every N-th image in file-name order (a video's frames overlap more than needed)
    #[arg(long, value_name = "N", default_value_t = 1)]
    every: usize,
    /// COLMAP's camera model, one camera for all photos when they share one size, else one
    /// each (the models trgs undistorts)
    #[arg(long, value_name = "MODEL", default_value = "SIMPLE_RADIAL",
          value_parser = clap::builder::PossibleValuesParser::new(trgs_core::lens::READ_MODELS))]
    camera_model: String,
    /// Keep the focal length COLMAP starts from, unrefined: the photos' EXIF focal length, or
    /// without EXIF (a video's frames) COLMAP's guess of 1.2 x the larger image side, wrong for
    /// most lenses. Only for a capture that only pans (a video along a facade), whose parallax
    /// is too small to refine it, and only once mapping without it has failed
    #[arg(long)]
    fix_focal: bool,
    /// When COLMAP splits the images into several models, keep the largest alone (without it,
    /// a split is an error that says how the images split)
    #[arg(long)]
    keep_largest: bool,
    /// The COLMAP program
    #[arg(long, value_name = "PATH", default_value = "colmap")]
    colmap: PathBuf,
    /// CPU threads for COLMAP [default: all]
    #[arg(long, value_name = "N", default_value_t = -1, allow_negative_numbers = true)]
    threads: i32,
}

pub fn run(matches: &clap::ArgMatches) -> Result<()> {
    let a = super::parsed::<Args>(matches);
    let options = PrepareOptions {
        input: a.input,
        out: a.out,
        matching: a.matching,
        every: a.every,
        camera_model: a.camera_model,
        fix_focal: a.fix_focal,
        keep_largest: a.keep_largest,
        colmap: a.colmap,
        threads: a.threads,
    };
    prepare(&options, &mut |line| println!("{line}"))?;
    Ok(())
}
