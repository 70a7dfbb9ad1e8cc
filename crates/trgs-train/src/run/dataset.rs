//! The folder a run trains on: the user's, or the built-in synthetic scene written into the run
//! folder once.
use super::config::RunConfig;
use anyhow::{Context, Result, bail};
use std::path::PathBuf;
use trgs_core::io::write_atomic;
use trgs_core::synthetic::write_generated;

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
