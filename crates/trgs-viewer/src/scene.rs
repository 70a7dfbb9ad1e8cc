//! What the viewer shows: a model read from disk (a run folder, a PLY with its planes.json, or a
//! .glb) with the dataset views found beside it, and the extent used to place the first camera
//! and scale the fly speed and the depth display.
use anyhow::{Context, Result};
use glam::DVec3;
use std::path::{Path, PathBuf};
use trgs_core::io::{RunMetrics, load_model, read_cameras_json};
use trgs_core::pipeline::ReflectionModel;
use trgs_core::scene::{Camera, Gaussians, Material, ReflectionPlane};

/// A model read from disk.
#[derive(Debug)]
pub struct LoadedModel {
    pub gaussians: Gaussians<f32>,
    pub planes: Vec<ReflectionPlane>,
    /// The reflection model the model was trained with (its ablations).
    pub reflection: ReflectionModel,
    /// The views of `cameras.json` in the run folder or beside the model file (none without).
    pub cameras: Vec<Camera>,
    /// The candidate planes a `--planes auto` run tried and dropped (its metrics.json's
    /// `candidates`), drawn as outlines only.
    pub dropped: Vec<ReflectionPlane>,
    /// The names of the run's test views (its metrics.json's `views`), marked in the view list.
    pub test_views: Vec<String>,
    /// The folder screenshots go to (under `screenshots/`): the run folder or the model's.
    pub folder: Option<PathBuf>,
    /// What the title bar says.
    pub name: String,
}

/// Read `path`: a run folder, a .ply (planes.json beside it) or a .glb.
pub fn load(path: &Path) -> Result<LoadedModel> {
    let model = load_model(path, None)?;
    let folder = if path.is_dir() { path.to_path_buf() } else { parent(&model.ply) };
    let cameras_path = folder.join("cameras.json");
    let cameras =
        if cameras_path.is_file() { read_cameras_json(&cameras_path)? } else { Vec::new() };
    let name = path.display().to_string();
    Ok(LoadedModel {
        gaussians: model.gaussians,
        planes: model.planes,
        reflection: model.reflection,
        cameras,
        dropped: dropped_candidates(&folder.join("metrics.json")),
        test_views: test_view_names(&folder.join("metrics.json")),
        folder: Some(folder),
        name,
    })
}

/// The test views of the run whose metrics are at `path` (`views[].name`); none when the file
/// is missing or unreadable.
pub fn test_view_names(path: &Path) -> Vec<String> {
    RunMetrics::read_if_any(path).map(|m| m.test_view_names()).unwrap_or_default()
}

/// The candidate planes that the run whose metrics are at `path` tried and dropped; none when
/// the file is missing or holds no candidates (the outline is a help, not the model: an
/// unreadable record does not stop the viewer).
pub fn dropped_candidates(path: &Path) -> Vec<ReflectionPlane> {
    let Some(metrics) = RunMetrics::read_if_any(path) else { return Vec::new() };
    let vec3 = |v: [f64; 3]| DVec3::from_array(v);
    metrics
        .candidates
        .iter()
        .filter(|r| r.proposed && !r.kept)
        .filter_map(|r| {
            let [w, h] = r.size?;
            let (c, n, t) = (vec3(r.centre?), vec3(r.normal?), vec3(r.axis?));
            let plane = ReflectionPlane::new(c, n, t, w, h, Material::Glass);
            plane.validate(0).is_ok().then_some(plane)
        })
        .collect()
}

fn parent(p: &Path) -> PathBuf {
    p.parent().map_or_else(|| PathBuf::from("."), Path::to_path_buf)
}

/// Where the Gaussians are: the mean of their centres and the radius holding 90% of them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Extent {
    pub centre: DVec3,
    pub radius: f64,
}

impl Extent {
    pub fn of(gaussians: &Gaussians<f32>) -> Self {
        let n = gaussians.len();
        if n == 0 {
            return Self { centre: DVec3::ZERO, radius: 1.0 };
        }
        let p = |m: &[f32; 3]| DVec3::new(f64::from(m[0]), f64::from(m[1]), f64::from(m[2]));
        let centre = gaussians.means.iter().map(p).sum::<DVec3>() / n as f64;
        let mut d: Vec<f64> = gaussians.means.iter().map(|m| (p(m) - centre).length()).collect();
        let k = (n * 9 / 10).min(n - 1);
        let (_, r, _) = d.select_nth_unstable_by(k, f64::total_cmp);
        Self { centre, radius: r.max(1e-3) }
    }
}

/// Samples of Gaussian centres kept on the CPU for the depth display's range.
const DEPTH_SAMPLES: usize = 20_000;

/// (near, far) for the depth display of `camera`: the 2nd and 98th percentiles of the depths of
/// (a sample of) the centres inside its view, so that the gray levels go to what is on screen,
/// whether the camera is inside a room or outside an object.
pub fn depth_range(means: &[[f32; 3]], camera: &Camera) -> [f32; 2] {
    let step = (means.len() / DEPTH_SAMPLES).max(1);
    let k = &camera.intrinsics;
    let (w, h) = (f64::from(k.width), f64::from(k.height));
    let mut z: Vec<f64> = means
        .iter()
        .step_by(step)
        .filter_map(|m| {
            let p = DVec3::new(f64::from(m[0]), f64::from(m[1]), f64::from(m[2]));
            let c = camera.pose.transform_point(p);
            let (x, y) = (k.fx * c.x / c.z + k.cx, k.fy * c.y / c.z + k.cy);
            (c.z > 0.2 && (0.0..w).contains(&x) && (0.0..h).contains(&y)).then_some(c.z)
        })
        .collect();
    if z.len() < 2 {
        return [0.2, 100.0];
    }
    z.sort_by(f64::total_cmp);
    let at = |q: f64| z[((z.len() - 1) as f64 * q) as usize];
    let near = at(0.02).max(0.2);
    [near as f32, at(0.98).max(near * 1.5) as f32]
}

/// Load `path` with the context a user needs when it fails.
pub fn load_for_viewer(path: &Path) -> Result<LoadedModel> {
    load(path).with_context(|| format!("cannot open {} in the viewer", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extent_ignores_the_farthest_tenth() {
        let mut g = Gaussians::zeros(100, 0);
        for (i, m) in g.means.iter_mut().enumerate() {
            *m = if i < 95 { [0.0, 0.0, (i % 2) as f32] } else { [1000.0, 0.0, 0.0] };
        }
        let e = Extent::of(&g);
        assert!(e.radius < 100.0, "{e:?}");
    }

    #[test]
    fn depth_range_spans_what_is_in_view() {
        let k = trgs_core::scene::Intrinsics::from_fov_x(1.0, 100, 100);
        let camera = Camera::new("c", k, trgs_core::scene::Pose::default());
        // In view at depths 1..=100, plus points behind and off to the side.
        let mut means: Vec<[f32; 3]> = (1..=100).map(|i| [0.0, 0.0, i as f32]).collect();
        means.extend([[0.0, 0.0, -5.0], [500.0, 0.0, 1.0]]);
        let [near, far] = depth_range(&means, &camera);
        assert!((2.0..=4.0).contains(&near) && (97.0..=99.0).contains(&far), "{near} {far}");
        assert_eq!(depth_range(&[], &camera), [0.2, 100.0]);
    }

    #[test]
    fn dropped_candidates_come_from_the_metrics() {
        let dir = trgs_core::scratch::ScratchDir::new("viewer-dropped");
        let path = dir.join("metrics.json");
        let record = |proposed: bool, kept: bool| {
            serde_json::json!({"proposed": proposed, "kept": kept, "centre": [0.0, 1.0, 0.0],
                "normal": [0.0, 0.0, 1.0], "axis": [1.0, 0.0, 0.0], "size": [2.0, 1.0]})
        };
        let metrics = serde_json::json!({"candidates":
            [record(true, false), record(true, true), record(false, false)]});
        std::fs::write(&path, metrics.to_string()).expect("write");
        let dropped = dropped_candidates(&path);
        assert_eq!(dropped.len(), 1, "only the one tried and dropped");
        assert_eq!((dropped[0].width, dropped[0].height), (2.0, 1.0));
        assert!(dropped_candidates(&dir.join("none.json")).is_empty());
        let view = |name: &str| serde_json::json!({"name": name, "psnr": 30.0, "ssim": 0.9});
        let metrics = serde_json::json!({"views": [view("a.png"), view("b.png")]});
        std::fs::write(&path, metrics.to_string()).expect("write");
        assert_eq!(test_view_names(&path), ["a.png", "b.png"]);
        assert!(test_view_names(&dir.join("none.json")).is_empty());
    }

    #[test]
    fn a_missing_file_is_named() {
        let err = load_for_viewer(Path::new("/nonexistent/model.ply")).expect_err("missing");
        assert!(format!("{err:#}").contains("/nonexistent/model.ply"), "{err:#}");
    }
}
