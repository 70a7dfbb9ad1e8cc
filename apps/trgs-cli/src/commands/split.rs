//! `split`: a capture into blocks that overlap, each a scene folder `trgs train` runs on
//! ([`crate::split`]), and the manifest that lists them.
use anyhow::Result;
use clap::Parser;
use std::path::PathBuf;

/// Split a COLMAP scene folder into blocks that overlap, to train apart (one `trgs train` per
/// block, on one machine after another or on several).
///
/// The blocks tile the ground (the plane across the cameras' mean up direction) by k-means of the
/// camera positions; a block's region is the ground nearer its centre than any other's, widened
/// by --margin, and holds the sparse points that fall in it. A view trains a block when enough of the points it observes lie in that region, so a
/// view can train several blocks; each test view belongs to the one block where most of its
/// points lie. Writes OUT/block_<k>/ (scene folders whose images/ and glass_masks/ link to the
/// capture's files) and OUT/blocks.json.
#[derive(Debug, Parser)]
#[command(
    name = "split",
    version,
    after_help = "Then, for each block: trgs train --data OUT/block_<k> --out RUNS/block_<k>"
)]
pub struct Args {
    /// The scene folder (COLMAP: sparse/0/ and images/)
    input: PathBuf,
    /// The folder of the blocks and their manifest
    #[arg(long)]
    out: PathBuf,
    /// How many blocks
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    blocks: u32,
    /// How far each region reaches past its border with a neighbour, in scene units [default:
    /// 15% of the median distance between neighbouring centres]
    #[arg(long, value_name = "DISTANCE", value_parser = crate::args::parse_non_negative)]
    margin: Option<f64>,
    /// The share of the points a view observes that must lie in a block's region for the view
    /// to train that block
    #[arg(long, value_name = "SHARE", default_value_t = 0.25, value_parser = crate::args::parse_share)]
    min_share: f64,
    /// The seed of the k-means
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

pub fn run(matches: &clap::ArgMatches) -> Result<()> {
    let a = super::parsed::<Args>(matches);
    let options = crate::split::SplitOptions {
        input: a.input,
        out: a.out.clone(),
        blocks: a.blocks as usize,
        margin: a.margin,
        min_share: a.min_share,
        seed: a.seed,
    };
    let manifest = crate::split::split(&options)?;
    for b in &manifest.blocks {
        println!(
            "{}: {} and {} test, {}; centre ({:.2}, {:.2}) on the ground",
            b.name,
            crate::wording::count(b.train_views, "training view"),
            b.test_views.len(),
            crate::wording::count(b.points, "point"),
            b.centre[0],
            b.centre[1]
        );
    }
    println!(
        "{} blocks (margin {:.3}) written to {}; manifest {}",
        manifest.blocks.len(),
        manifest.margin,
        a.out.display(),
        a.out.join(crate::split::MANIFEST).display()
    );
    Ok(())
}
