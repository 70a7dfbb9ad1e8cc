//! The folder a run trains on: the user's, or the built-in synthetic scene written into the run
//! folder once.
use super::config::RunConfig;
use anyhow::{Context, Result, bail};
use std::path::PathBuf;
use trgs_core::io::write_atomic;
use trgs_core::synthetic::{generate, write_dataset};

/// The file that a complete demo dataset ends with: it names the built-in scene the folder holds
/// (its `--demo-scene` value). It is written last, so a folder without it (a write cut short) is
/// written again; a run that asks for another scene in the same `--out` is refused instead of
/// training on a folder that mixes the two.
pub const DEMO_SCENE_MARKER: &str = "demo_scene.txt";

/// The scene folder of `config`, and a line saying so when the built-in scene was written now.
pub fn dataset_dir(config: &RunConfig) -> Result<(PathBuf, Option<String>)> {
    if let Some(d) = &config.data {
        return Ok((d.clone(), None));
    }
    let scene = config.demo_scene;
    let dir = config.out.join("dataset");
    let marker = dir.join(DEMO_SCENE_MARKER);
    if let Ok(found) = std::fs::read_to_string(&marker) {
        let held = super::config::DemoScene::parse(found.trim()).with_context(|| {
            format!("{}: {:?} is not a built-in scene's name", marker.display(), found.trim())
        })?;
        if held != scene {
            bail!(
                "{} holds the built-in scene `--demo-scene {}`, not `{}`: choose another --out, \
                 or remove that folder",
                dir.display(),
                held.name(),
                scene.name()
            );
        }
        return Ok((dir, None));
    }
    write_dataset(&generate(&scene.config()), &dir)
        .with_context(|| format!("writing the demo scene to {}", dir.display()))?;
    write_atomic(&marker, format!("{}\n", scene.name()).as_bytes())?;
    let note = format!("wrote the built-in synthetic {} to {}", scene.description(), dir.display());
    Ok((dir, Some(note)))
}
