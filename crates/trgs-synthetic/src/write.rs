//! Writing a [`SyntheticScene`] as a trgs scene folder, with its ground truth beside it:
//!
//! ```text
//! images/<name>                 composites (8-bit RGB PNG)
//! sparse/0/{cameras,images,points3D}.bin   COLMAP model (the lens's), tracks consistent
//! glass_masks/<name>            8-bit labels, masked training views only
//! planes.json                   the planes' materials per label (only when there are panes)
//! test_views.txt                the test split
//! gt/transmission/<name>        ground-truth transmission C_t
//! gt/planes.json                the truth planes (centre, normal, axis, size, R0)
//! ```
use std::path::Path;

use std::sync::Mutex;

use super::config::{SyntheticConfig, SyntheticLens};
use super::plan::{SyntheticScene, plan};
use super::render_views::for_each_view;
use trgs_core::io::{ColmapCamera, ColmapImage, ColmapModel, ColmapPoint, FormatError};
use trgs_core::lens::Distortion;
use trgs_core::scene::Camera;

/// Write the scene folder described in the module documentation into `dir`.
pub fn write_dataset(scene: &SyntheticScene, dir: &Path) -> Result<(), FormatError> {
    for (i, cam) in scene.cameras.iter().enumerate() {
        write_view(dir, cam, &scene.images[i], &scene.transmission[i], scene.masks[i].as_ref())?;
    }
    write_model(dir, &scene_parts(scene))
}

/// Generate the scene of `config` and write it into `dir` view by view as the views are traced,
/// holding a few at a time: the same folder as `write_dataset(&generate(config), dir)`, for
/// scenes too large to hold (200 photos of 12 MP).
pub fn write_generated(config: &SyntheticConfig, dir: &Path) -> Result<(), FormatError> {
    let plan = plan(config);
    let failure: Mutex<Option<FormatError>> = Mutex::new(None);
    for_each_view(&plan.layout, |i, view| {
        let view = plan.photo(view);
        let mask = plan.masked.contains(&i).then_some(&view.labels);
        if let Err(e) = write_view(dir, &plan.cameras[i], &view.image, &view.transmission, mask)
            && let Ok(mut first) = failure.lock()
        {
            first.get_or_insert(e);
        }
    });
    if let Some(e) = failure.into_inner().ok().flatten() {
        return Err(e);
    }
    let parts = Parts {
        cameras: &plan.cameras,
        lens: plan.lens,
        points: &plan.points,
        tracks: &plan.tracks,
        planes: &plan.planes,
        test_views: &plan.test_views,
    };
    write_model(dir, &parts)
}

/// One view's files: its photo, its ground-truth transmission and its glass mask, if it has one.
fn write_view(
    dir: &Path,
    cam: &Camera,
    image: &trgs_core::image::Image<f32>,
    transmission: &trgs_core::image::Image<f32>,
    mask: Option<&trgs_core::image::Image<u8>>,
) -> Result<(), FormatError> {
    write_photo(&dir.join("images").join(&cam.name), image)?;
    write_photo(&dir.join("gt").join("transmission").join(&cam.name), transmission)?;
    if let Some(mask) = mask {
        let name = Path::new(&cam.name).with_extension("png");
        trgs_core::io::write_glass_mask(&dir.join("glass_masks").join(name), mask)?;
    }
    Ok(())
}

/// What the folder holds beside the views' images.
struct Parts<'a> {
    cameras: &'a [Camera],
    lens: SyntheticLens,
    points: &'a [([f64; 3], [u8; 3])],
    tracks: &'a [Vec<usize>],
    planes: &'a [trgs_core::scene::ReflectionPlane],
    test_views: &'a [String],
}

fn scene_parts(scene: &SyntheticScene) -> Parts<'_> {
    Parts {
        cameras: &scene.cameras,
        lens: scene.lens,
        points: &scene.points,
        tracks: &scene.tracks,
        planes: &scene.planes,
        test_views: &scene.test_views,
    }
}

/// The COLMAP model, the planes' materials and truth, and the test split.
fn write_model(dir: &Path, parts: &Parts<'_>) -> Result<(), FormatError> {
    colmap_model_of(parts).write_binary(&dir.join("sparse").join("0"))?;
    if !parts.planes.is_empty() {
        // The input carries materials only: the geometry must be estimated from the masks (the
        // truth is in gt/planes.json, which the reader never reads).
        let materials: Vec<_> = parts.planes.iter().map(|p| p.material).collect();
        trgs_core::io::write_plane_materials(&dir.join("planes.json"), &materials)?;
        trgs_core::io::write_planes_json(&dir.join("gt").join("planes.json"), parts.planes)?;
    }
    trgs_core::io::write_test_views(&dir.join("test_views.txt"), parts.test_views)
}

/// A photo as its name says: JPEG (quality 95) for `.jpg`, PNG otherwise.
fn write_photo(path: &Path, image: &trgs_core::image::Image<f32>) -> Result<(), FormatError> {
    if path.extension().is_some_and(|e| e == "jpg") {
        trgs_core::io::write_jpeg_rgb(path, image, 95)
    } else {
        trgs_core::io::write_png_rgb(path, image)
    }
}

/// Pixel position of world point `p` in the photo of `camera` through `lens` (COLMAP and trgs
/// both put pixel centres at +0.5), or `None` behind the camera.
fn pixel(camera: &Camera, lens: SyntheticLens, p: [f64; 3]) -> Option<[f64; 2]> {
    let q = camera.pose.transform_point(glam::DVec3::from_array(p));
    if q.z <= 0.0 {
        return None;
    }
    let (x, y) = (q.x / q.z, q.y / q.z);
    let (x, y) = lens.distortion().map_or((x, y), |d| d.distort(x, y));
    let k = &camera.intrinsics;
    Some([k.fx * x + k.cx, k.fy * y + k.cy])
}

/// COLMAP's parameter list of a camera matrix with `lens`.
fn colmap_params(k: &trgs_core::scene::Intrinsics, lens: SyntheticLens) -> Vec<f64> {
    let mut params = vec![k.fx, k.fy, k.cx, k.cy];
    match lens.distortion() {
        None => {}
        Some(Distortion::RadialTangential { k, p }) => params.extend([k[0], k[1], p[0], p[1]]),
        Some(Distortion::Fisheye { k }) => params.extend(k),
    }
    params
}

/// The scene's cameras, poses and sparse points as a COLMAP model: one camera of the lens's model
/// per distinct intrinsics, image ids from 1 in view order, point ids from 1, and each point's track
/// naming the images that see it with the index of its observation in their `points2d`.
pub fn colmap_model(scene: &SyntheticScene) -> ColmapModel {
    colmap_model_of(&scene_parts(scene))
}

fn colmap_model_of(scene: &Parts<'_>) -> ColmapModel {
    let mut cameras: Vec<ColmapCamera> = Vec::new();
    let mut images = Vec::with_capacity(scene.cameras.len());
    for (i, cam) in scene.cameras.iter().enumerate() {
        let k = &cam.intrinsics;
        let params = colmap_params(k, scene.lens);
        let same = |c: &ColmapCamera| {
            c.width == u64::from(k.width) && c.height == u64::from(k.height) && c.params == params
        };
        let camera_id = match cameras.iter().find(|c| same(c)) {
            Some(c) => c.id,
            None => {
                let id = cameras.len() as u32 + 1;
                cameras.push(ColmapCamera {
                    id,
                    model: scene.lens.colmap_model().to_string(),
                    width: u64::from(k.width),
                    height: u64::from(k.height),
                    params,
                });
                id
            }
        };
        images.push(ColmapImage {
            id: i as u32 + 1,
            qvec: cam.pose.qvec(),
            tvec: cam.pose.translation.to_array(),
            camera_id,
            name: cam.name.clone(),
            points2d: Vec::new(),
        });
    }
    let mut points = Vec::with_capacity(scene.points.len());
    for (j, ((xyz, rgb), views)) in scene.points.iter().zip(scene.tracks).enumerate() {
        let id = j as u64 + 1;
        let mut track = Vec::with_capacity(views.len());
        for &v in views {
            // The generator only lists cameras the point projects into, in front of them.
            let Some(uv) = pixel(&scene.cameras[v], scene.lens, *xyz) else { continue };
            let image = &mut images[v];
            track.push((image.id, image.points2d.len() as u32));
            image.points2d.push((uv, id as i64));
        }
        // Observations are exact projections of the stored point: zero reprojection error.
        points.push(ColmapPoint { id, xyz: *xyz, rgb: *rgb, error: 0.0, track });
    }
    ColmapModel { cameras, images, points }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate;
    use trgs_core::scratch::ScratchDir;

    #[test]
    fn colmap_tracks_match_observations() {
        let scene = generate(&SyntheticConfig::small());
        let model = colmap_model(&scene);
        assert_eq!(model.cameras.len(), 1);
        assert_eq!(model.images.len(), scene.cameras.len());
        assert_eq!(model.points.len(), scene.points.len());
        for p in &model.points {
            assert!(p.track.len() >= 2);
            for &(image_id, idx) in &p.track {
                let image = &model.images[image_id as usize - 1];
                assert_eq!(image.id, image_id);
                let (uv, pid) = image.points2d[idx as usize];
                assert_eq!(pid, p.id as i64);
                let (w, h) = (scene.cameras[0].width(), scene.cameras[0].height());
                assert!(
                    uv[0] >= 0.0 && uv[1] >= 0.0 && uv[0] < f64::from(w) && uv[1] < f64::from(h)
                );
            }
        }
        let observations: usize = model.images.iter().map(|i| i.points2d.len()).sum();
        let track_len: usize = model.points.iter().map(|p| p.track.len()).sum();
        assert_eq!(observations, track_len);
    }

    #[test]
    fn written_view_by_view_is_the_same_folder() {
        let config = SyntheticConfig::small();
        let (a, b) = (ScratchDir::new("synth-held"), ScratchDir::new("synth-streamed"));
        write_dataset(&generate(&config), &a).expect("write held");
        write_generated(&config, &b).expect("write streamed");
        let files = |d: &Path| {
            let mut out = Vec::new();
            let mut stack = vec![d.to_path_buf()];
            while let Some(p) = stack.pop() {
                for e in std::fs::read_dir(&p).expect("dir").flatten() {
                    if e.path().is_dir() {
                        stack.push(e.path());
                    } else {
                        let rel = e.path().strip_prefix(d).expect("inside").to_path_buf();
                        out.push((rel, std::fs::read(e.path()).expect("read")));
                    }
                }
            }
            out.sort();
            out
        };
        let (fa, fb) = (files(&a), files(&b));
        assert_eq!(fa.len(), fb.len());
        for ((pa, da), (pb, db)) in fa.iter().zip(&fb) {
            assert_eq!(pa, pb);
            assert!(da == db, "{} differs", pa.display());
        }
    }

    #[test]
    fn photos_larger_than_the_traced_size_are_enlarged_jpegs() {
        let config = SyntheticConfig::small();
        let plan = crate::plan::plan_traced_at(&config, 32);
        assert_eq!(plan.enlarged, Some((64, 48)));
        assert_eq!(plan.layout.cameras[0].width(), 32, "traced at 32 px");
        assert_eq!((plan.cameras[0].width(), plan.cameras[0].name.as_str()), (64, "view_000.jpg"));
        assert!(plan.test_views.iter().all(|n| n.ends_with(".jpg")));
        let traced = crate::render_views::render_view(&plan.layout, &plan.layout.cameras[0]);
        let photo = plan.photo(traced);
        assert_eq!((photo.image.width, photo.labels.height), (64, 48));
        let dir = ScratchDir::new("synth-jpeg");
        write_photo(&dir.join("a.jpg"), &photo.image).expect("write");
        let bytes = std::fs::read(dir.join("a.jpg")).expect("read");
        assert_eq!(&bytes[..2], &[0xFF, 0xD8], "a JPEG");
    }

    #[test]
    fn dataset_folder_has_every_file() {
        let scene = generate(&SyntheticConfig::small());
        let dir = trgs_core::scratch::ScratchDir::new("synth-write");
        if let Err(e) = write_dataset(&scene, &dir) {
            panic!("write_dataset: {e}");
        }
        for name in ["sparse/0/cameras.bin", "sparse/0/images.bin", "sparse/0/points3D.bin"] {
            assert!(dir.join(name).is_file(), "{name} missing");
        }
        for name in ["planes.json", "test_views.txt", "gt/planes.json"] {
            assert!(dir.join(name).is_file(), "{name} missing");
        }
        for (cam, mask) in scene.cameras.iter().zip(&scene.masks) {
            assert!(dir.join("images").join(&cam.name).is_file());
            assert!(dir.join("gt/transmission").join(&cam.name).is_file());
            assert_eq!(dir.join("glass_masks").join(&cam.name).is_file(), mask.is_some());
        }
    }
}
