//! `merge`: the trained blocks of `trgs split` into one model ([`crate::merge`]).
use anyhow::Result;
use clap::Parser;
use std::path::PathBuf;

/// Merge the trained blocks of `trgs split` into one run folder.
///
/// Each block gives the Gaussians on its own part of the ground (its region without the margin
/// it trained with). Where the capture has glass masks, each block's plane is held against
/// them: the planes that cover one mask label best are that pane, the one that covers it best
/// (the block that saw it whole) stands for it with its glass Gaussians, moved onto all of the
/// capture's masks of that label, R0 is their mean by how well each covers it, and a plane that
/// covers no label is left out. Without masks (or
/// with --by-geometry), planes that several blocks found for one pane (same material, normals
/// within --max-angle, offsets within --max-offset, rectangles within --max-gap of each other)
/// become one plane over the union of their rectangles, its normal and R0 weighted by area.
/// OUT is a run folder for trgs eval, view, render and export.
#[derive(Debug, Parser)]
#[command(
    name = "merge",
    version,
    after_help = "Then: trgs eval --model OUT --data SCENE (the whole capture's test views)"
)]
pub struct Args {
    /// The folder trgs split wrote (with blocks.json)
    blocks: PathBuf,
    /// The folder of the blocks' runs: RUNS/block_<k> for each block
    #[arg(long, value_name = "RUNS")]
    runs: PathBuf,
    /// The merged run folder
    #[arg(long)]
    out: PathBuf,
    /// Largest angle between two blocks' normals of one pane, degrees
    #[arg(long, value_name = "DEG", default_value_t = 5.0, value_parser = crate::args::parse_non_negative)]
    max_angle: f64,
    /// Largest distance of one's centre from the other's plane, scene units [default: 1% of the
    /// distance between neighbouring blocks]
    #[arg(long, value_name = "DISTANCE", value_parser = crate::args::parse_non_negative)]
    max_offset: Option<f64>,
    /// Largest gap between their rectangles, scene units [default: --max-offset's: they touch]
    #[arg(long, value_name = "DISTANCE", value_parser = crate::args::parse_non_negative)]
    max_gap: Option<f64>,
    /// Tell the planes of one pane by geometry even where the capture has glass masks
    #[arg(long)]
    by_geometry: bool,
}

pub fn run(matches: &clap::ArgMatches) -> Result<()> {
    let a = super::parsed::<Args>(matches);
    let options = crate::merge::MergeOptions {
        blocks: a.blocks,
        runs: a.runs,
        out: a.out.clone(),
        max_angle_deg: a.max_angle,
        max_offset: a.max_offset,
        max_gap: a.max_gap,
        by_geometry: a.by_geometry,
    };
    let (report, gaussians, planes) = crate::merge::merge(&options)?;
    for (b, kept) in report.kept.iter().enumerate() {
        println!("block_{b}: {kept} Gaussians on its own ground");
    }
    for (k, from) in report.planes_from.iter().enumerate() {
        let sources: Vec<String> =
            from.iter().map(|(b, p)| format!("block_{b} plane {}", p + 1)).collect();
        match report.labels.get(k) {
            Some((label, iou)) => println!(
                "plane {}: mask label {label}, from {} (covers it by {iou:.2} IoU; the others \
                 give R0)",
                k + 1,
                sources.join(", ")
            ),
            None => println!("plane {}: from {}", k + 1, sources.join(", ")),
        }
    }
    for (b, p, why) in &report.dropped {
        println!("block_{b} plane {}: left out, {why}", p + 1);
    }
    println!(
        "{gaussians} Gaussians and {} written to {}",
        crate::wording::count(planes, "plane"),
        a.out.display()
    );
    Ok(())
}
