//! `merge`'s stages: the runs of the blocks `split` wrote into one run folder
//! (`trgs_core::blocks::merge` decides what each block gives).
use crate::split::{MANIFEST, Manifest};
use anyhow::{Context, Result, bail};
use glam::{DVec2, DVec3};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::{Path, PathBuf};
use trgs_core::blocks::merge::{MergeReport, PaneEvidence, SamePane, TrainedBlock, merge_blocks};
use trgs_core::blocks::{Ground, Regions};
use trgs_core::image::Image;
use trgs_core::io::{ColmapModel, RunMetrics, SceneFolder, colmap_dir};
use trgs_core::io::{
    load_model, read_cameras_json, write_atomic, write_cameras_json, write_planes_json, write_ply,
};
use trgs_core::pipeline::ReflectionModel;
use trgs_core::scene::Camera;
use trgs_train::{Resolution, load_masked_views};

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
    /// None: the same as the offset.
    pub max_gap: Option<f64>,
    /// Group the planes by geometry even where the capture has glass masks.
    pub by_geometry: bool,
}

/// The intersection over union with a mask label below which a block's plane covers no pane
/// (a partial view of a pane from a neighbouring block still scores about half).
const MIN_MASK_IOU: f64 = 0.3;

/// The longest side the masks are checked at: enough to tell which plane covers a pane best.
const MASK_CHECK_SIDE: u32 = 640;

/// Refuse a block's run whose views (its cameras.json) are not those of the block's folder: a
/// run of an earlier split (made again with other settings into the same folder, or another
/// split's runs) would be cut to this split's cells, leaving holes where they reach past the
/// region it trained.
fn check_trained_on(run: &Path, trained: &[Camera], folder: &Path) -> Result<()> {
    let block = SceneFolder::open(folder)?;
    let theirs: HashSet<&str> = trained.iter().map(|c| c.name.as_str()).collect();
    let ours: HashSet<&str> = block.views.iter().map(|v| v.camera.name.as_str()).collect();
    if theirs != ours {
        let missing = ours.difference(&theirs).count();
        let other = theirs.difference(&ours).count();
        bail!(
            "{}: trained on other views than the block's folder {} holds ({missing} of its {} \
             views missing, {other} others): a run of an earlier split; train the block again \
             (remove the run folder), or merge with the blocks it was trained on",
            run.display(),
            folder.display(),
            ours.len()
        );
    }
    Ok(())
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
    let mut reflection_model: Option<ReflectionModel> = None;
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
            let trained = read_cameras_json(&cams)?;
            check_trained_on(&run, &trained, &o.blocks.join(&b.folder))?;
            for c in trained {
                cameras.entry(c.name.clone()).or_insert(c);
            }
        }
        if reflection_model.is_none() {
            reflection_model = reflection_model_of(&run);
        }
        blocks.push(TrainedBlock { gaussians: model.gaussians, planes: model.planes });
    }
    let max_offset = o.max_offset.unwrap_or(0.01 * regions.spacing());
    let same = SamePane {
        max_angle_deg: o.max_angle_deg,
        max_offset,
        max_gap: o.max_gap.unwrap_or(max_offset),
    };
    // The capture that was split: its masks tell the panes apart, its COLMAP model the seams.
    let capture = SceneFolder::open(&manifest.source);
    let masked = match (&capture, o.by_geometry) {
        (_, true) => Vec::new(),
        (Ok(folder), false) => masked_views(folder)?,
        (Err(e), false) => bail!(
            "opening the capture the blocks were split from, {} (for its glass masks; \
             --by-geometry merges without them): {e:#}",
            manifest.source.display()
        ),
    };
    let masks: Vec<(&Camera, &Image<u8>)> =
        masked.iter().filter_map(|v| Some((&v.camera, v.mask.as_ref()?))).collect();
    let evidence = if masks.is_empty() {
        PaneEvidence::Geometry(same)
    } else {
        PaneEvidence::Masks { masks: &masks, min_iou: MIN_MASK_IOU }
    };
    let (gaussians, planes, report) = merge_blocks(&blocks, &ground, &regions, evidence);
    std::fs::create_dir_all(&o.out)
        .with_context(|| format!("creating the output folder {}", o.out.display()))?;
    write_ply(&o.out.join("model.ply"), &gaussians)?;
    write_planes_json(&o.out.join("planes.json"), &planes)?;
    let cameras: Vec<_> = cameras.into_values().collect();
    write_cameras_json(&o.out.join("cameras.json"), &cameras)?;
    let seams = capture.ok().and_then(|folder| seam_views(&folder, &ground, &regions));
    let metrics = serde_json::json!({
        "merged_from": manifest.blocks.iter().map(|b| &b.name).collect::<Vec<_>>(),
        "kept_per_block": report.kept,
        "planes_from": report.planes_from,
        "plane_labels": report.labels,
        "planes_dropped": report.dropped,
        "seam_views": seams,
        "gaussians": gaussians.len(),
        "reflection_model": reflection_model,
    });
    write_atomic(&o.out.join("metrics.json"), serde_json::to_string_pretty(&metrics)?.as_bytes())?;
    Ok((report, gaussians.len(), planes.len()))
}

/// The capture's test views that look across a seam between blocks
/// ([`Regions::spans_a_seam`], by the sparse points each observes), for `trgs eval` to score
/// apart; None where its COLMAP model cannot be read.
fn seam_views(folder: &SceneFolder, ground: &Ground, regions: &Regions) -> Option<Vec<String>> {
    let model = ColmapModel::read(&colmap_dir(&folder.root)?).ok()?;
    let at: HashMap<u64, DVec2> =
        model.points.iter().map(|p| (p.id, ground.project(DVec3::from_array(p.xyz)))).collect();
    let test: HashSet<&str> = folder.test_views.iter().map(String::as_str).collect();
    let seams = model
        .images
        .iter()
        .filter(|im| test.contains(im.name.as_str()))
        .filter(|im| {
            let seen: Vec<DVec2> = im
                .points2d
                .iter()
                .filter_map(|&(_, id)| u64::try_from(id).ok().and_then(|id| at.get(&id).copied()))
                .collect();
            regions.spans_a_seam(&seen)
        })
        .map(|im| im.name.clone())
        .collect();
    Some(seams)
}

/// The masked views of the capture that was split (none when it has no masks).
fn masked_views(folder: &SceneFolder) -> Result<Vec<trgs_train::View>> {
    if folder.views.iter().all(|v| v.mask_path.is_none()) {
        return Ok(Vec::new());
    }
    load_masked_views(folder, Resolution::LongSide(MASK_CHECK_SIDE))
        .with_context(|| format!("loading the glass masks of {}", folder.root.display()))
}

/// The reflection model a block's run trained with (its metrics.json), if it says.
fn reflection_model_of(run: &Path) -> Option<ReflectionModel> {
    RunMetrics::read_if_any(&run.join("metrics.json"))?.reflection_model
}
