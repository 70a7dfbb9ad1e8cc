//! The model a scene keeps: COLMAP's mapper makes one model per group of images it could join
//! (`0/`, `1/`, ...); the largest is the scene, written as `sparse/0/` in COLMAP's binary
//! layout. Fewer than half of the images in it is an error that says what to try; the images
//! in the other models are named in a note, as they are not trained on.
use anyhow::{Context, Result, bail};
use std::path::Path;
use trgs_core::io::ColmapModel;

/// The model kept and what was left out.
#[derive(Debug)]
pub struct Kept {
    /// Images given to COLMAP.
    pub images: usize,
    /// Images in the kept model.
    pub registered: usize,
    pub points: usize,
    /// The image counts of the other models, largest first.
    pub dropped: Vec<usize>,
}

impl Kept {
    /// What to tell the user besides the counts.
    pub fn notes(&self) -> Vec<String> {
        let mut lines = vec![format!(
            "model: {} of {} images registered ({:.0}%), {} points",
            self.registered,
            self.images,
            100.0 * self.registered as f64 / self.images.max(1) as f64,
            self.points
        )];
        if !self.dropped.is_empty() {
            let sizes: Vec<String> = self.dropped.iter().map(usize::to_string).collect();
            lines.push(format!(
                "model: COLMAP also made {} smaller models ({} images), not joined to this one \
                 and not kept: their images are not in the scene",
                self.dropped.len(),
                sizes.join(", ")
            ));
        }
        lines
    }
}

/// Keep the largest model under `models` as `target` (binary); `images` is how many images
/// COLMAP was given.
pub fn keep_largest(models: &Path, target: &Path, images: usize) -> Result<Kept> {
    let mut found: Vec<ColmapModel> = Vec::new();
    let entries =
        std::fs::read_dir(models).with_context(|| format!("listing {}", models.display()))?;
    for e in entries {
        let dir = e.with_context(|| format!("listing {}", models.display()))?.path();
        if dir.is_dir() {
            found.push(ColmapModel::read(&dir)?);
        }
    }
    found.sort_by_key(|m| std::cmp::Reverse(m.images.len()));
    let Some(largest) = found.first() else {
        bail!(
            "COLMAP registered none of the {images} images (no model): the images may not \
             overlap enough, or be too blurred or alike; for a video try --matching sequential \
             and a smaller --every, for photos more overlap between neighbouring shots"
        );
    };
    let kept = Kept {
        images,
        registered: largest.images.len(),
        points: largest.points.len(),
        dropped: found[1..].iter().map(|m| m.images.len()).collect(),
    };
    if 2 * kept.registered < images {
        let split = if kept.dropped.is_empty() {
            String::new()
        } else {
            format!(" (it split them into {} models)", found.len())
        };
        bail!(
            "COLMAP registered only {} of the {images} images in its largest model{split}: \
             fewer than half. Try --matching exhaustive for photos taken in no order, \
             --matching sequential with a smaller --every for a video, --fix-focal for a \
             capture that only pans; or retake with more overlap between neighbouring shots",
            kept.registered
        );
    }
    std::fs::create_dir_all(target).with_context(|| format!("creating {}", target.display()))?;
    largest.write_binary(target)?;
    Ok(kept)
}
