//! The folder a run trains on (the user's, or the built-in synthetic scene written into the run
//! folder once) and its loading, checked against the device first.
use super::config::{PlaneSource, RunConfig};
use crate::data::{self, LoadOptions, LoadProgress, TrainingData};
use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};
use std::time::Instant;
use trgs_core::io::write_atomic;
use trgs_render::GpuContext;
use trgs_synthetic::write_generated;

/// The file that a complete demo dataset ends with: it names the built-in scene the folder holds
/// (its `--demo-scene` value, then the other flags that shape it: `RunConfig::demo_flags`). It
/// is written last, so a folder without it (a write cut short) is written again; a run that asks
/// for another scene in the same `--out` is refused instead of training on a folder that mixes
/// the two.
pub const DEMO_SCENE_MARKER: &str = "demo_scene.txt";

/// The scene folder of `config`, and a line saying so when the built-in scene was written now.
pub fn dataset_dir(config: &RunConfig) -> Result<(PathBuf, Option<String>)> {
    if let Some(d) = &config.data {
        return Ok((d.clone(), None));
    }
    let scene = config.demo_scene;
    let wanted = config.demo_flags();
    let dir = config.out.join("dataset");
    let marker = dir.join(DEMO_SCENE_MARKER);
    if let Ok(found) = std::fs::read_to_string(&marker) {
        let found = found.trim();
        let (name, rest) = found.split_once(' ').unwrap_or((found, ""));
        let held = super::config::DemoScene::parse(name).with_context(|| {
            format!("{}: {name:?} is not a built-in scene's name", marker.display())
        })?;
        // Old markers name the window scene `glass`: compare the scene, then the other flags.
        let held_flags = format!("{} {rest}", held.name()).trim().to_string();
        if held_flags != wanted {
            bail!(
                "{} holds the built-in scene `--demo-scene {held_flags}`, not `{wanted}`: choose \
                 another --out, or remove that folder",
                dir.display(),
            );
        }
        return Ok((dir, None));
    }
    let demo = config.demo_config();
    write_generated(&demo, &dir)
        .with_context(|| format!("writing the demo scene to {}", dir.display()))?;
    write_atomic(&marker, format!("{wanted}\n").as_bytes())?;
    let note = format!(
        "wrote the built-in synthetic {} ({}x{}, {} views, {} photos) to {}",
        scene.description(),
        demo.width,
        demo.height,
        demo.views + demo.room_views,
        demo.lens.colmap_model(),
        dir.display()
    );
    Ok((dir, Some(note)))
}

/// Every view's training size against the device's limits and the training views' GPU memory
/// budget, before the photos load: a view too large is refused now, naming it, rather than at
/// its first step.
fn check_view_sizes(
    ctx: &GpuContext,
    folder: &trgs_core::io::SceneFolder,
    config: &RunConfig,
) -> Result<()> {
    let budget = crate::trainer::targets::budget_bytes(ctx, config.target_memory);
    for v in &folder.views {
        let (w, h) = data::target_size(v.camera.width(), v.camera.height(), config.resolution())?;
        let at = || format!("view {} ({})", v.camera.name, v.image_path.display());
        crate::losses::check_frame_size(ctx, w, h).with_context(at)?;
        let bytes = crate::trainer::targets::bytes_of_target(w, h, v.mask_path.is_some());
        crate::trainer::targets::check_budget(budget, &v.camera.name, bytes).with_context(at)?;
    }
    Ok(())
}

/// The dataset of `config` at its training resolution, with lines saying what it holds.
pub(super) fn load_data(
    ctx: &GpuContext,
    config: &RunConfig,
    data_dir: &Path,
    note: &mut impl FnMut(String),
    loading: &LoadProgress<'_>,
) -> Result<TrainingData> {
    let folder = trgs_core::io::SceneFolder::open(data_dir)
        .with_context(|| format!("opening the scene folder {}", data_dir.display()))?;
    check_view_sizes(ctx, &folder, config)?;
    let started = Instant::now();
    let options =
        LoadOptions { resolution: config.resolution(), evaluate: None, progress: Some(loading) };
    let mut data = TrainingData::load(&folder, &options)?;
    let seconds = started.elapsed().as_secs_f64();
    let source = config.plane_source(!data.materials.is_empty());
    if source == PlaneSource::Masks && data.materials.is_empty() {
        bail!(
            "--planes masks: {} has no glass masks (glass_masks/ beside images/); paint them, or \
             let --planes auto propose the planes from the scene",
            data_dir.display()
        );
    }
    let had_masks = !data.materials.is_empty();
    if source != PlaneSource::Masks {
        // Auto must not learn from the masks it ignores (the mask loss reads them).
        data.materials.clear();
        for view in data.train.iter_mut().chain(data.test.iter_mut()) {
            view.mask = None;
        }
    }
    let (w, h) = data.size();
    note(format!(
        "dataset {}: {} training and {} test views at {w}x{h}, {} sparse points, extent {:.2} \
         (loaded in {seconds:.1} s)",
        data_dir.display(),
        data.train.len(),
        data.test.len(),
        data.points.len(),
        data.extent
    ));
    for line in &data.notes {
        note(line.clone());
    }
    let ignored = if had_masks { " (its glass masks are ignored)" } else { "" };
    note(match source {
        PlaneSource::None if config.no_planes || config.planes.is_some() => {
            format!("--planes none: training plain 3DGS{ignored}")
        }
        PlaneSource::None => "no glass masks: no reflection planes, training plain 3DGS \
                              (--planes auto proposes them from the scene)"
            .into(),
        PlaneSource::Masks => format!(
            "glass masks with labels {:?}: planes are initialised after stage 1",
            data.materials
        ),
        PlaneSource::Auto => format!(
            "--planes auto: planes are proposed from the scene after stage 1 and kept where \
             they pay{ignored}"
        ),
    });
    let ablations = config.ablations.names();
    if !ablations.is_empty() {
        note(format!("ablations: {}", ablations.join(", ")));
    }
    Ok(data)
}
