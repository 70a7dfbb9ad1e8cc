//! `merge`'s stages: the runs of the blocks `split` wrote into one run folder
//! (`trgs_core::blocks::merge` decides what each block gives).
use crate::split::{MANIFEST, Manifest};
use anyhow::{Context, Result, bail};
use glam::{DVec2, DVec3};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use trgs_core::blocks::merge::{MergeReport, SamePane, TrainedBlock, merge_blocks};
use trgs_core::blocks::{Ground, Regions};
use trgs_core::io::{
    load_model, read_cameras_json, write_atomic, write_cameras_json, write_planes_json, write_ply,
};

/// How to merge.
#[derive(Clone, Debug)]
pub struct MergeOptions {
    /// The folder `split` wrote (blocks.json).
    pub blocks: PathBuf,
    /// The folder of the blocks' runs, one per block named as the block.
    pub runs: PathBuf,
    pub out: PathBuf,
    pub max_angle_deg: f64,
    /// None: 1% of the blocks' spacing.
    pub max_offset: Option<f64>,
    /// None: the split's margin.
    pub max_gap: Option<f64>,
}

/// The merged model written to `o.out` as a run folder (model.ply, planes.json, cameras.json,
/// metrics.json with the reflection model and what came from where).
pub fn merge(o: &MergeOptions) -> Result<(MergeReport, usize, usize)> {
    let path = o.blocks.join(MANIFEST);
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("{}: cannot read the blocks' manifest", path.display()))?;
    let manifest: Manifest = serde_json::from_str(&text)
        .with_context(|| format!("{}: not a manifest of trgs split", path.display()))?;
    let ground =
        Ground { up: DVec3::from_array(manifest.up), axes: manifest.axes.map(DVec3::from_array) };
    let regions =
        Regions { centres: manifest.blocks.iter().map(|b| DVec2::from_array(b.centre)).collect() };
    let mut blocks = Vec::new();
    let mut cameras = BTreeMap::new();
    let mut reflection_model = serde_json::Value::Null;
    for b in &manifest.blocks {
        let run = o.runs.join(&b.name);
        if !run.is_dir() {
            bail!(
                "{}: no run of {} (train it: trgs train --data {} --out {})",
                run.display(),
                b.name,
                o.blocks.join(&b.folder).display(),
                run.display()
            );
        }
        let model = load_model(&run, None)?;
        let cams = run.join("cameras.json");
        if cams.is_file() {
            for c in read_cameras_json(&cams)? {
                cameras.entry(c.name.clone()).or_insert(c);
            }
        }
        if reflection_model.is_null() {
            reflection_model = reflection_model_of(&run);
        }
        blocks.push(TrainedBlock { gaussians: model.gaussians, planes: model.planes });
    }
    let same = SamePane {
        max_angle_deg: o.max_angle_deg,
        max_offset: o.max_offset.unwrap_or(0.01 * regions.spacing()),
        max_gap: o.max_gap.unwrap_or(manifest.margin),
    };
    let (gaussians, planes, report) = merge_blocks(&blocks, &ground, &regions, same);
    std::fs::create_dir_all(&o.out)
        .with_context(|| format!("creating the output folder {}", o.out.display()))?;
    write_ply(&o.out.join("model.ply"), &gaussians)?;
    write_planes_json(&o.out.join("planes.json"), &planes)?;
    let cameras: Vec<_> = cameras.into_values().collect();
    write_cameras_json(&o.out.join("cameras.json"), &cameras)?;
    let metrics = serde_json::json!({
        "merged_from": manifest.blocks.iter().map(|b| &b.name).collect::<Vec<_>>(),
        "kept_per_block": report.kept,
        "planes_from": report.planes_from,
        "gaussians": gaussians.len(),
        "reflection_model": reflection_model,
    });
    write_atomic(&o.out.join("metrics.json"), serde_json::to_string_pretty(&metrics)?.as_bytes())?;
    Ok((report, gaussians.len(), planes.len()))
}

/// The reflection model a block's run trained with (its metrics.json), or null.
fn reflection_model_of(run: &Path) -> serde_json::Value {
    std::fs::read_to_string(run.join("metrics.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .map(|m| m["reflection_model"].clone())
        .unwrap_or(serde_json::Value::Null)
}
