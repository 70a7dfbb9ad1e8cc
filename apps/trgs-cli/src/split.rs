//! `split`'s stages: a COLMAP scene folder into block folders that overlap, and their manifest
//! (`trgs_core::blocks` decides what each block holds). A block folder is a scene folder of its
//! own: `images/` and `glass_masks/` link to the capture's files, `sparse/0/` holds the block's
//! cameras, views and points (tracks cut to its views), `test_views.txt` its test views (an
//! empty list when it has none, so that no block holds out views of its own), and `planes.json`
//! is the capture's.
use anyhow::{Context, Result, bail};
use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use trgs_core::blocks::{Assignment, BlockPlan, Ground, Regions, kmeans, plan_blocks};
use trgs_core::io::{ColmapModel, SceneFolder, colmap_dir, write_atomic, write_test_views};
use trgs_core::scene::Pose;

/// The fewest training views a block gets (`Assignment::min_views`).
const MIN_BLOCK_VIEWS: usize = 8;

/// The manifest's file name in the output folder.
pub const MANIFEST: &str = "blocks.json";

/// How to split.
#[derive(Clone, Debug)]
pub struct SplitOptions {
    pub input: PathBuf,
    pub out: PathBuf,
    pub blocks: usize,
    /// The regions' widening in scene units; None: 15% of the centres' spacing.
    pub margin: Option<f64>,
    /// The share of a view's points that must lie in a block's widened region for it to train
    /// the block.
    pub min_share: f64,
    pub seed: u64,
}

/// What `split` wrote: the ground, the regions and each block, for `merge` and for a driver
/// (Ray, Slurm) that runs one `trgs train` per block.
#[derive(Debug, Serialize, Deserialize)]
pub struct Manifest {
    pub source: PathBuf,
    pub up: [f64; 3],
    pub axes: [[f64; 3]; 2],
    pub margin: f64,
    pub blocks: Vec<BlockRecord>,
}

#[derive(Debug, Serialize, Deserialize)]
pub struct BlockRecord {
    pub name: String,
    /// The block's scene folder, relative to the manifest.
    pub folder: String,
    /// Its centre on the ground (the region is the Voronoi cell of the centres, widened).
    pub centre: [f64; 2],
    pub train_views: usize,
    pub test_views: Vec<String>,
    pub points: usize,
}

/// Split `o.input` into `o.blocks` block folders under `o.out` and write the manifest.
pub fn split(o: &SplitOptions) -> Result<Manifest> {
    if o.blocks == 0 {
        bail!("--blocks must be at least 1");
    }
    let folder = SceneFolder::open(&o.input)
        .with_context(|| format!("opening the scene folder {}", o.input.display()))?;
    let Some(sparse) = colmap_dir(&o.input) else {
        bail!(
            "{}: split reads COLMAP scene folders (sparse/0/ and images/); this one has none",
            o.input.display()
        );
    };
    let model = ColmapModel::read(&sparse)?;
    if model.points.is_empty() {
        bail!("{}: no sparse points to place the blocks by", sparse.display());
    }
    let ups: Vec<DVec3> = model
        .images
        .iter()
        .map(|im| Pose::from_qvec_tvec(im.qvec, im.tvec).rotation.transpose() * DVec3::NEG_Y)
        .collect();
    let Some(ground) = Ground::from_ups(&ups) else {
        bail!("{}: the cameras' up directions cancel out; no ground to tile", sparse.display());
    };
    let on_ground: Vec<DVec2> =
        model.points.iter().map(|p| ground.project(DVec3::from_array(p.xyz))).collect();
    // The blocks follow where the cameras went (VastGaussian's partition): the sparse points of
    // a facade or a street reach far past the capture (the far side, reflections), and k-means
    // of them would cut by distance rather than along the path.
    let stations: Vec<DVec2> = model
        .images
        .iter()
        .map(|im| ground.project(Pose::from_qvec_tvec(im.qvec, im.tvec).centre()))
        .collect();
    let regions = Regions { centres: kmeans(&stations, o.blocks, o.seed) };
    if regions.centres.len() < o.blocks {
        bail!(
            "{} blocks asked for, but the cameras stand at {} places",
            o.blocks,
            regions.centres.len()
        );
    }
    let margin = o.margin.unwrap_or(0.15 * regions.spacing());
    let index: HashMap<u64, usize> =
        model.points.iter().enumerate().map(|(i, p)| (p.id, i)).collect();
    let observations: Vec<Vec<usize>> = model
        .images
        .iter()
        .map(|im| {
            let mut seen: Vec<usize> = im
                .points2d
                .iter()
                .filter_map(|&(_, id)| {
                    u64::try_from(id).ok().and_then(|id| index.get(&id).copied())
                })
                .collect();
            seen.sort_unstable();
            seen.dedup();
            seen
        })
        .collect();
    let test: HashSet<&str> = folder.test_views.iter().map(String::as_str).collect();
    let is_test: Vec<bool> =
        model.images.iter().map(|im| test.contains(im.name.as_str())).collect();
    let assignment = Assignment { margin, min_share: o.min_share, min_views: MIN_BLOCK_VIEWS };
    let plans = plan_blocks(&regions, &on_ground, &observations, &is_test, assignment);
    if let Some(b) = plans.iter().position(|p| p.train.is_empty()) {
        bail!(
            "block {b}: no view sees its region (its points are seen by test views alone, or not \
             at all); split into fewer blocks"
        );
    }
    std::fs::create_dir_all(&o.out)
        .with_context(|| format!("creating the output folder {}", o.out.display()))?;
    let mut blocks = Vec::new();
    for (b, plan) in plans.iter().enumerate() {
        let name = format!("block_{b}");
        let points = write_block(&o.out.join(&name), &o.input, &folder, &model, plan)
            .with_context(|| format!("writing {name}"))?;
        blocks.push(BlockRecord {
            folder: name.clone(),
            name,
            centre: regions.centres[b].to_array(),
            train_views: plan.train.len(),
            test_views: plan.test.iter().map(|&v| model.images[v].name.clone()).collect(),
            points,
        });
    }
    let manifest = Manifest {
        source: std::fs::canonicalize(&o.input).unwrap_or_else(|_| o.input.clone()),
        up: ground.up.to_array(),
        axes: ground.axes.map(|a| a.to_array()),
        margin,
        blocks,
    };
    let json = serde_json::to_string_pretty(&manifest)?;
    write_atomic(&o.out.join(MANIFEST), json.as_bytes())?;
    Ok(manifest)
}

/// One block's scene folder; returns how many points it holds (those of its region that one of
/// its views sees).
fn write_block(
    dir: &Path,
    input: &Path,
    folder: &SceneFolder,
    model: &ColmapModel,
    plan: &BlockPlan,
) -> Result<usize> {
    let views: HashSet<usize> = plan.train.iter().chain(&plan.test).copied().collect();
    let points: HashSet<usize> = plan.points.iter().copied().collect();
    let kept_ids: HashSet<u64> = points.iter().map(|&i| model.points[i].id).collect();
    let image_ids: HashSet<u32> = views.iter().map(|&v| model.images[v].id).collect();
    let mut sub = ColmapModel::default();
    for (v, im) in model.images.iter().enumerate() {
        if !views.contains(&v) {
            continue;
        }
        let mut im = im.clone();
        // A keypoint whose point is outside the block keeps its place (track indices refer to
        // it) but no longer names a point.
        for (_, id) in &mut im.points2d {
            if u64::try_from(*id).is_ok_and(|id| !kept_ids.contains(&id)) {
                *id = -1;
            }
        }
        sub.images.push(im);
    }
    let camera_ids: HashSet<u32> = sub.images.iter().map(|im| im.camera_id).collect();
    sub.cameras = model.cameras.iter().filter(|c| camera_ids.contains(&c.id)).cloned().collect();
    for (i, p) in model.points.iter().enumerate() {
        if !points.contains(&i) {
            continue;
        }
        let mut p = p.clone();
        p.track.retain(|(image, _)| image_ids.contains(image));
        if !p.track.is_empty() {
            sub.points.push(p);
        }
    }
    let sparse = dir.join("sparse").join("0");
    std::fs::create_dir_all(&sparse)?;
    sub.write_binary(&sparse)?;
    let by_name: HashMap<&str, &trgs_core::io::ViewSpec> =
        folder.views.iter().map(|v| (v.camera.name.as_str(), v)).collect();
    for im in &sub.images {
        let Some(view) = by_name.get(im.name.as_str()) else {
            bail!("image {:?} of the COLMAP model is not among the scene's views", im.name);
        };
        link(&view.image_path, &dir.join("images").join(&im.name))?;
        if let Some(mask) = &view.mask_path {
            let file = mask.file_name().unwrap_or_default();
            let rel = Path::new(&im.name).with_file_name(file);
            link(mask, &dir.join("glass_masks").join(rel))?;
        }
    }
    let test: Vec<String> = plan.test.iter().map(|&v| model.images[v].name.clone()).collect();
    write_test_views(&dir.join("test_views.txt"), &test)?;
    let planes = input.join("planes.json");
    if planes.is_file() {
        let bytes =
            std::fs::read(&planes).with_context(|| format!("reading {}", planes.display()))?;
        write_atomic(&dir.join("planes.json"), &bytes)?;
    }
    Ok(sub.points.len())
}

/// `at` made a link to `target` (absolute; a copy where links need privileges), replacing what
/// a previous split left there.
fn link(target: &Path, at: &Path) -> Result<()> {
    if let Some(parent) = at.parent() {
        std::fs::create_dir_all(parent)?;
    }
    let target =
        std::fs::canonicalize(target).with_context(|| format!("resolving {}", target.display()))?;
    if at.symlink_metadata().is_ok() {
        std::fs::remove_file(at).with_context(|| format!("replacing {}", at.display()))?;
    }
    #[cfg(unix)]
    let made = std::os::unix::fs::symlink(&target, at);
    // Elsewhere links need privileges: a copy.
    #[cfg(not(unix))]
    let made = std::fs::copy(&target, at).map(|_| ());
    made.with_context(|| format!("linking {} to {}", at.display(), target.display()))
}
