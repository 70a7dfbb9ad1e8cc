//! The model a scene keeps: COLMAP's mapper makes one model per group of images it could join
//! (`0/`, `1/`, ...); the largest is the scene, written as `sparse/0/` in COLMAP's binary
//! layout. Fewer than half of the images in it is an error that says what to try; so is a split
//! into several models, unless the user keeps the largest alone (`--keep-largest`): the other
//! models' images would silently not be trained on.
use super::Matching;
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

/// The largest model COLMAP made, checked, and what was left out.
#[derive(Debug)]
pub struct Picked {
    model: ColmapModel,
    pub kept: Kept,
}

impl Picked {
    /// An error when COLMAP split the images into several models: it says how, and what to try.
    pub fn refuse_split(&self) -> Result<()> {
        let k = &self.kept;
        if k.dropped.is_empty() {
            return Ok(());
        }
        let sizes: Vec<String> = k.dropped.iter().map(usize::to_string).collect();
        bail!(
            "COLMAP split the images into {} models: the largest holds {} of the {} images, the \
             others {} (their images would not be trained on). Try --matching exhaustive (photos) \
             or a smaller --every (a video) to join them, or pass --keep-largest to keep the \
             largest alone",
            k.dropped.len() + 1,
            k.registered,
            k.images,
            sizes.join(", ")
        );
    }

    /// Write the model as `target` (binary): beside its place, then renamed into it, so that a
    /// scene folder holds all three files or none. Its parent must exist or be creatable.
    pub fn write(self, target: &Path) -> Result<Kept> {
        let partial = target.with_extension("partial");
        if partial.exists() {
            std::fs::remove_dir_all(&partial)
                .with_context(|| format!("removing {}", partial.display()))?;
        }
        std::fs::create_dir_all(&partial)
            .with_context(|| format!("creating {}", partial.display()))?;
        self.model.write_binary(&partial)?;
        std::fs::rename(&partial, target)
            .with_context(|| format!("renaming {} to {}", partial.display(), target.display()))?;
        Ok(self.kept)
    }
}

/// What to try when too few images register, after matching by `matching`: never the matching
/// the run already used.
fn what_to_try(matching: Matching) -> &'static str {
    match matching {
        Matching::Exhaustive => {
            "for a video try --matching sequential and a smaller --every; for photos, more \
             overlap between neighbouring shots"
        }
        Matching::Sequential => {
            "try a smaller --every, --matching exhaustive for photos taken in no order, or \
             retake with more overlap between neighbouring shots"
        }
    }
}

/// The largest model under `models` (one folder per model); `images` is how many images COLMAP
/// was given, matched by `matching`. Fewer than half of them in it is an error that says what to
/// try.
pub fn pick_largest(models: &Path, images: usize, matching: Matching) -> Result<Picked> {
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
    if found.is_empty() {
        bail!(
            "COLMAP registered none of the {images} images (no model): the images may not \
             overlap enough, or be too blurred or alike; {}",
            what_to_try(matching)
        );
    }
    let largest = found.remove(0);
    let kept = Kept {
        images,
        registered: largest.images.len(),
        points: largest.points.len(),
        dropped: found.iter().map(|m| m.images.len()).collect(),
    };
    if 2 * kept.registered < images {
        let split = if kept.dropped.is_empty() {
            String::new()
        } else {
            format!(" (it split them into {} models)", kept.dropped.len() + 1)
        };
        bail!(
            "COLMAP registered only {} of the {images} images in its largest model{split}: \
             fewer than half; {}, or --fix-focal for a capture that only pans",
            kept.registered,
            what_to_try(matching)
        );
    }
    Ok(Picked { model: largest, kept })
}

#[cfg(test)]
mod tests {
    use super::*;
    use trgs_core::io::{ColmapCamera, ColmapImage};
    use trgs_core::scratch::ScratchDir;

    /// A model of `n` images (names `prefix_i.jpg`) and no points, in `dir`.
    fn model(dir: &Path, prefix: &str, n: u32) {
        let camera = ColmapCamera {
            id: 1,
            model: "PINHOLE".into(),
            width: 64,
            height: 48,
            params: vec![50.0, 50.0, 32.0, 24.0],
        };
        let images = (1..=n)
            .map(|id| ColmapImage {
                id,
                qvec: [1.0, 0.0, 0.0, 0.0],
                tvec: [0.0, 0.0, f64::from(id)],
                camera_id: 1,
                name: format!("{prefix}_{id}.jpg"),
                points2d: Vec::new(),
            })
            .collect();
        let m = ColmapModel { cameras: vec![camera], images, points: Vec::new() };
        std::fs::create_dir_all(dir).expect("folder");
        m.write_binary(dir).expect("model");
    }

    #[test]
    fn the_largest_model_is_kept_and_a_split_is_named() {
        let dir = ScratchDir::new("prepare-models");
        let models = dir.join("sparse");
        model(&models.join("0"), "a", 3);
        model(&models.join("1"), "b", 7);
        let picked = pick_largest(&models, 12, Matching::Exhaustive).expect("7 of 12");
        assert_eq!((picked.kept.registered, picked.kept.dropped.clone()), (7, vec![3]));
        let split = picked.refuse_split().expect_err("a split").to_string();
        assert!(split.contains("into 2 models") && split.contains("--keep-largest"), "{split}");
        let target = dir.join("scene").join("0");
        std::fs::create_dir_all(dir.join("scene")).expect("folder");
        let kept = picked.write(&target).expect("written");
        assert_eq!(kept.registered, 7);
        let written = ColmapModel::read(&target).expect("sparse/0");
        assert!(written.images.iter().all(|i| i.name.starts_with("b_")));
        assert!(!target.with_extension("partial").exists(), "renamed into place");
    }

    #[test]
    fn fewer_than_half_or_no_model_is_an_error_that_says_what_to_try() {
        let dir = ScratchDir::new("prepare-models-few");
        let models = dir.join("sparse");
        std::fs::create_dir_all(&models).expect("folder");
        let none = pick_largest(&models, 5, Matching::Exhaustive).expect_err("none").to_string();
        assert!(none.contains("registered none of the 5 images"), "{none}");
        assert!(none.contains("--matching sequential"), "{none}");
        model(&models.join("0"), "a", 2);
        let few = pick_largest(&models, 5, Matching::Sequential).expect_err("2 of 5").to_string();
        assert!(few.contains("registered only 2 of the 5"), "{few}");
        // A sequential run is not told to match sequentially.
        assert!(few.contains("--matching exhaustive") && few.contains("--every"), "{few}");
        assert!(!few.contains("--matching sequential"), "{few}");
        let whole = pick_largest(&models, 2, Matching::Exhaustive).expect("2 of 2");
        assert!(whole.refuse_split().is_ok());
    }
}
