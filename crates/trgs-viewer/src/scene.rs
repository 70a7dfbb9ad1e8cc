//! What the viewer shows: a model read from disk (a run folder, a PLY with its planes.json, or a
//! .glb) with the dataset views found beside it, and the extent used to place the first camera
//! and scale the fly speed and the depth display.
use anyhow::{Context, Result};
use glam::DVec3;
use std::path::{Path, PathBuf};
use trgs_core::io::{load_model, read_cameras_json};
use trgs_core::scene::{Camera, Gaussians, ReflectionPlane};

/// A model read from disk.
#[derive(Debug)]
pub struct LoadedModel {
    pub gaussians: Gaussians<f32>,
    pub planes: Vec<ReflectionPlane>,
    /// The views of `cameras.json` in the run folder or beside the model file (none without).
    pub cameras: Vec<Camera>,
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
    Ok(LoadedModel { gaussians: model.gaussians, planes: model.planes, cameras, name })
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

    /// (near, far) of the inverse-depth display seen from `eye`.
    pub fn depth_range(&self, eye: DVec3) -> [f32; 2] {
        let d = (eye - self.centre).length();
        let near = (d - self.radius).max(0.05 * self.radius).max(1e-3);
        let far = (d + self.radius).max(near * 1.01);
        [near as f32, far as f32]
    }
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
        let [near, far] = e.depth_range(e.centre + DVec3::new(0.0, 0.0, -10.0));
        assert!(near > 0.0 && far > near);
    }

    #[test]
    fn a_missing_file_is_named() {
        let err = load_for_viewer(Path::new("/nonexistent/model.ply")).expect_err("missing");
        assert!(format!("{err:#}").contains("/nonexistent/model.ply"), "{err:#}");
    }
}
