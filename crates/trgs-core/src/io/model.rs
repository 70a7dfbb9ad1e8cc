//! Loading a trained model: a Gaussian PLY (trgs or any INRIA-layout file) and its planes, or a
//! `.glb` with `KHR_gaussian_splatting` (Gaussians and planes in one file), or an `.spz`
//! (Gaussians only).
use super::{FormatError, RunMetrics, check_finished_run, read_glb, read_planes_json, read_ply};
use crate::pipeline::ReflectionModel;
use crate::scene::{Gaussians, ReflectionPlane};
use std::path::{Path, PathBuf};

/// A model to render.
#[derive(Debug)]
pub struct Model {
    pub gaussians: Gaussians<f32>,
    pub planes: Vec<ReflectionPlane>,
    /// The file the Gaussians came from (.ply or .glb).
    pub ply: PathBuf,
    /// The reflection model the run trained with: its ablations, from the `metrics.json` that
    /// `train` writes beside the model (the full model when there is none).
    pub reflection: ReflectionModel,
}

/// The reflection model recorded in the `metrics.json` beside `ply` or in the folder `path`.
/// A file without the record (another tool's) gives the full model.
fn trained_reflection_model(path: &Path, ply: &Path) -> ReflectionModel {
    let candidates = [ply.with_file_name("metrics.json"), path.join("metrics.json")];
    let Some(text) = candidates.iter().find_map(|p| std::fs::read_to_string(p).ok()) else {
        return ReflectionModel::default();
    };
    RunMetrics::parse(&text).ok().and_then(|m| m.reflection_model).unwrap_or_default()
}

/// The PLY of `path`: the file itself, or in a folder `model.ply`, else the INRIA layout's
/// `point_cloud/iteration_<largest>/point_cloud.ply`.
pub fn find_ply(path: &Path) -> Result<PathBuf, FormatError> {
    if path.is_file() {
        return Ok(path.to_path_buf());
    }
    if !path.is_dir() {
        return Err(FormatError::new(
            path,
            "no such file or folder (expected a .ply, a .glb or a run folder)",
        ));
    }
    let direct = path.join("model.ply");
    if direct.is_file() {
        return Ok(direct);
    }
    let iterations = path.join("point_cloud");
    let mut best: Option<(u64, PathBuf)> = None;
    if let Ok(entries) = std::fs::read_dir(&iterations) {
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            let Some(n) = name.strip_prefix("iteration_").and_then(|n| n.parse::<u64>().ok())
            else {
                continue;
            };
            let ply = e.path().join("point_cloud.ply");
            if ply.is_file() && best.as_ref().is_none_or(|(b, _)| n > *b) {
                best = Some((n, ply));
            }
        }
    }
    best.map(|(_, p)| p).ok_or_else(|| {
        FormatError::new(
            path,
            "no model.ply and no point_cloud/iteration_*/point_cloud.ply in this folder",
        )
    })
}

/// Load the Gaussians of `path` and the planes of `planes` (or, when None, of a `planes.json`
/// beside the PLY or in the run folder; none found means no planes: plain 3DGS).
pub fn load_model(path: &Path, planes: Option<&Path>) -> Result<Model, FormatError> {
    refuse_unfinished_run(path)?;
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("glb")) {
        let (gaussians, mut inside) = read_glb(path)?;
        checked(path, &gaussians)?;
        if let Some(p) = planes {
            inside = load_model_planes(p)?;
        }
        let reflection = trained_reflection_model(path, path);
        return Ok(Model { gaussians, planes: inside, ply: path.to_path_buf(), reflection });
    }
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("spz")) {
        // SPZ holds plain Gaussians: planes only when given.
        let gaussians = super::read_spz(path)?;
        checked(path, &gaussians)?;
        let planes = match planes {
            Some(p) => load_model_planes(p)?,
            None => Vec::new(),
        };
        let reflection = trained_reflection_model(path, path);
        return Ok(Model { gaussians, planes, ply: path.to_path_buf(), reflection });
    }
    let ply = find_ply(path)?;
    let gaussians = read_ply(&ply)?;
    checked(&ply, &gaussians)?;
    let planes_path = match planes {
        Some(p) => Some(p.to_path_buf()),
        None => [ply.with_file_name("planes.json"), path.join("planes.json")]
            .into_iter()
            .find(|p| p.is_file()),
    };
    let planes = match planes_path {
        Some(pp) => load_model_planes(&pp)?,
        None => Vec::new(),
    };
    let reflection = trained_reflection_model(path, &ply);
    Ok(Model { gaussians, planes, ply, reflection })
}

/// A model in the folder of a run that has not finished is what an earlier run or a partial
/// write left: refused, whether the folder or a file in it was named.
fn refuse_unfinished_run(path: &Path) -> Result<(), FormatError> {
    if path.is_dir() {
        return check_finished_run(path);
    }
    match path.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(dir) => check_finished_run(dir),
        None => check_finished_run(Path::new(".")),
    }
}

/// What the renderer would refuse at upload (a NaN, a zero quaternion), as an error that names
/// the file, when it is read.
fn checked(path: &Path, g: &crate::scene::Gaussians<f32>) -> Result<(), FormatError> {
    crate::scene::validate_gaussians(g).map_err(|e| FormatError::new(path, e.to_string()))
}

/// The trained planes of a planes.json (every plane must have its geometry).
fn load_model_planes(path: &Path) -> Result<Vec<ReflectionPlane>, FormatError> {
    let mut out = Vec::new();
    for (i, spec) in read_planes_json(path)?.into_iter().enumerate() {
        match spec.plane {
            Some(p) => out.push(p),
            None => {
                return Err(FormatError::new(
                    path,
                    format!(
                        "plane {i} (label {}) has a material but no geometry; rendering needs \
                         trained planes (centre, normal, axis, width, height)",
                        spec.label
                    ),
                ));
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::write_ply;
    use crate::scene::{Gaussians, Population};

    #[test]
    fn a_model_the_renderer_would_refuse_is_an_error_naming_its_file() {
        let dir = crate::scratch::ScratchDir::new("model-checked");
        let mut g = Gaussians::<f32>::empty(0);
        for i in 0..3 {
            g.push(
                [i as f32, 0.0, 2.0],
                [1.0, 0.0, 0.0, 0.0],
                [-2.0; 3],
                0.0,
                &[],
                Population::Primary,
            );
        }
        let ply = dir.join("model.ply");
        write_ply(&ply, &g).expect("write");
        assert_eq!(load_model(&dir, None).expect("valid").gaussians.len(), 3);
        g.rotations[1] = [0.0; 4];
        write_ply(&ply, &g).expect("write");
        let err = load_model(&dir, None).expect_err("zero quaternion").to_string();
        assert!(err.contains("model.ply") && err.contains("Gaussian 1"), "{err}");
        assert!(err.contains("zero quaternion"), "{err}");
    }

    #[test]
    fn a_model_in_an_unfinished_runs_folder_is_refused() {
        let dir = crate::scratch::ScratchDir::new("model-unfinished");
        let mut g = Gaussians::<f32>::empty(0);
        g.push([0.0, 0.0, 2.0], [1.0, 0.0, 0.0, 0.0], [-2.0; 3], 0.0, &[], Population::Primary);
        write_ply(&dir.join("model.ply"), &g).expect("write");
        let run = crate::io::UnfinishedRun { iterations: 30, checkpoint_step: 10 };
        crate::io::write_unfinished_run(&dir, &run).expect("mark");
        for path in [dir.to_path_buf(), dir.join("model.ply")] {
            let err = load_model(&path, None).expect_err("unfinished").to_string();
            assert!(err.contains("unfinished training run"), "{err}");
        }
        crate::io::clear_unfinished_run(&dir).expect("finished");
        assert_eq!(load_model(&dir, None).expect("finished").gaussians.len(), 1);
    }

    #[test]
    fn the_reflection_model_of_an_ablation_run_comes_from_its_metrics() {
        let dir = crate::scratch::ScratchDir::new("model-reflection");
        let mut g = Gaussians::<f32>::empty(0);
        g.push([0.0, 0.0, 2.0], [1.0, 0.0, 0.0, 0.0], [-2.0; 3], 0.0, &[], Population::Primary);
        let ply = dir.join("model.ply");
        write_ply(&ply, &g).expect("write");
        // No metrics.json (another tool's model): the full model.
        assert_eq!(load_model(&dir, None).expect("load").reflection, ReflectionModel::default());
        let metrics =
            r#"{"psnr": 30.0, "reflection_model": {"fresnel": false, "intensity": true}}"#;
        std::fs::write(dir.join("metrics.json"), metrics).expect("metrics");
        let want = ReflectionModel { fresnel: false, intensity: true };
        // From the run folder, and from the PLY beside it.
        assert_eq!(load_model(&dir, None).expect("load").reflection, want);
        assert_eq!(load_model(&ply, None).expect("load").reflection, want);
        // Another tool's metrics.json (no record, or not JSON) leaves the full model.
        std::fs::write(dir.join("metrics.json"), "PSNR 30").expect("metrics");
        assert_eq!(load_model(&ply, None).expect("load").reflection, ReflectionModel::default());
    }
}
