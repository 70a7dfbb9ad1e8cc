//! COLMAP sparse models (`cameras`, `images`, `points3D`) in COLMAP's binary and text layouts,
//! and the conversion of one registered image into a trgs [`Camera`].
//!
//! The readers check what the rest of trgs relies on (parameter counts, finite poses, camera
//! references, unique ids) so that a bad model fails here, naming the file and the record or line,
//! rather than as a NaN deep inside training.
mod binary;
mod models;
#[cfg(test)]
mod tests;
mod text;

use std::collections::{HashMap, HashSet};
use std::path::Path;

use super::FormatError;
use crate::lens::{Lens, Undistortion, colmap_camera_model};
use crate::scene::{Camera, Intrinsics, Pose};
use models::known_models;
pub(crate) use models::model_by_name;

/// One COLMAP camera (intrinsics shared by any number of images).
#[derive(Clone, Debug, PartialEq)]
pub struct ColmapCamera {
    pub id: u32,
    /// COLMAP's model name, e.g. `"PINHOLE"`.
    pub model: String,
    pub width: u64,
    pub height: u64,
    pub params: Vec<f64>,
}

/// One registered image: world-to-camera pose `x_cam = R(qvec) x_world + tvec`.
#[derive(Clone, Debug, PartialEq)]
pub struct ColmapImage {
    pub id: u32,
    /// Rotation quaternion (w, x, y, z).
    pub qvec: [f64; 4],
    pub tvec: [f64; 3],
    pub camera_id: u32,
    pub name: String,
    /// Keypoints `([x, y], point3D_id)`; the id is -1 for a keypoint without a 3D point.
    pub points2d: Vec<([f64; 2], i64)>,
}

/// One triangulated point and its track `(image_id, point2D_idx)`.
#[derive(Clone, Debug, PartialEq)]
pub struct ColmapPoint {
    pub id: u64,
    pub xyz: [f64; 3],
    pub rgb: [u8; 3],
    pub error: f64,
    pub track: Vec<(u32, u32)>,
}

/// A whole sparse model. Images are sorted by id; cameras and points keep the file's order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ColmapModel {
    pub cameras: Vec<ColmapCamera>,
    pub images: Vec<ColmapImage>,
    pub points: Vec<ColmapPoint>,
}

/// Parsed records and where each came from, for later cross-checks.
type Located<T> = Vec<(T, Location)>;

/// Where a record came from ("camera record 3 (of 5)", "line 17"), made into words only for a
/// message: a model holds millions of points.
#[derive(Clone, Copy, Debug)]
enum Location {
    Record { kind: &'static str, index: u64, count: u64 },
    Line(usize),
}

impl std::fmt::Display for Location {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Location::Record { kind, index, count } => {
                write!(f, "{kind} record {index} (of {count})")
            }
            Location::Line(n) => write!(f, "line {n}"),
        }
    }
}

impl ColmapModel {
    /// Read `dir/cameras.bin, images.bin, points3D.bin` if `cameras.bin` exists, else the `.txt`
    /// files.
    pub fn read(dir: &Path) -> Result<Self, FormatError> {
        if dir.join("cameras.bin").is_file() {
            Self::read_binary(dir)
        } else if dir.join("cameras.txt").is_file() {
            Self::read_text(dir)
        } else {
            Err(FormatError::new(
                dir,
                "no COLMAP model here: expected cameras.bin, images.bin and points3D.bin, \
                 or cameras.txt, images.txt and points3D.txt",
            ))
        }
    }

    pub fn read_binary(dir: &Path) -> Result<Self, FormatError> {
        let cameras = binary::read_cameras(&dir.join("cameras.bin"))?;
        let images_path = dir.join("images.bin");
        let images = binary::read_images(&images_path)?;
        let points = binary::read_points(&dir.join("points3D.bin"))?;
        assemble(cameras, images, points, &dir.join("cameras.bin"), &images_path)
    }

    pub fn read_text(dir: &Path) -> Result<Self, FormatError> {
        let cameras = text::read_cameras(&dir.join("cameras.txt"))?;
        let images_path = dir.join("images.txt");
        let images = text::read_images(&images_path)?;
        let points = text::read_points(&dir.join("points3D.txt"))?;
        assemble(cameras, images, points, &dir.join("cameras.txt"), &images_path)
    }

    /// Write `dir/{cameras,images,points3D}.bin` in COLMAP's layout.
    pub fn write_binary(&self, dir: &Path) -> Result<(), FormatError> {
        binary::write(self, dir)
    }

    /// Write `dir/{cameras,images,points3D}.txt` as COLMAP does (comment header, two lines per
    /// image, floats in shortest round-trip form so text and binary load identically).
    pub fn write_text(&self, dir: &Path) -> Result<(), FormatError> {
        text::write(self, dir)
    }

    /// The trgs camera of an image (named by the image's name) and, for a camera model with lens
    /// distortion, how its photo is undistorted: the camera is then the pinhole view
    /// [`Undistortion::new`] chooses (as COLMAP's `image_undistorter` would). The model does not
    /// remember its folder, so the error's path is `cameras`; [`super::SceneFolder`] replaces it
    /// with the real file.
    pub fn camera(
        &self,
        image: &ColmapImage,
    ) -> Result<(Camera, Option<Undistortion>), FormatError> {
        let lens = self.lens(self.camera_of(image)?)?;
        posed(image, lens)
    }

    /// [`Self::camera`] of every image, in order, each COLMAP camera's undistortion made once
    /// (a sweep of its photo's border) and shared by its images.
    pub fn views(&self) -> Result<Vec<(Camera, Option<Undistortion>)>, FormatError> {
        let mut lenses = HashMap::new();
        for cam in &self.cameras {
            lenses.insert(cam.id, self.lens(cam)?);
        }
        self.images
            .iter()
            .map(|image| {
                let cam = self.camera_of(image)?;
                posed(image, lenses[&cam.id].clone())
            })
            .collect()
    }

    fn camera_of(&self, image: &ColmapImage) -> Result<&ColmapCamera, FormatError> {
        self.cameras.iter().find(|c| c.id == image.camera_id).ok_or_else(|| {
            FormatError::new(
                "cameras",
                format!(
                    "image {} ({}) uses camera {}, which does not exist",
                    image.id, image.name, image.camera_id
                ),
            )
        })
    }

    /// The pinhole intrinsics of a COLMAP camera and its undistortion, if its model distorts.
    pub fn lens(
        &self,
        cam: &ColmapCamera,
    ) -> Result<(Intrinsics, Option<Undistortion>), FormatError> {
        let fail =
            |problem: String| FormatError::new("cameras", format!("camera {}: {problem}", cam.id));
        let size = |v: u64, what: &str| {
            u32::try_from(v).map_err(|_| fail(format!("{what} {v} is too large")))
        };
        let (width, height) = (size(cam.width, "width")?, size(cam.height, "height")?);
        let (intrinsics, distortion) =
            colmap_camera_model(&cam.model, &cam.params, width, height).map_err(&fail)?;
        intrinsics.validate().map_err(|e| fail(e.to_string()))?;
        let Some(distortion) = distortion else { return Ok((intrinsics, None)) };
        let lens = Lens { model: cam.model.clone(), intrinsics, distortion };
        let undistortion = Undistortion::new(lens).map_err(|e| fail(e.to_string()))?;
        Ok((undistortion.pinhole, Some(undistortion)))
    }
}

/// An image's camera: its pose with its COLMAP camera's pinhole intrinsics.
fn posed(
    image: &ColmapImage,
    (intrinsics, undistortion): (Intrinsics, Option<Undistortion>),
) -> Result<(Camera, Option<Undistortion>), FormatError> {
    let pose = Pose::from_qvec_tvec(image.qvec, image.tvec);
    pose.validate().map_err(|e| {
        FormatError::new("cameras", format!("image {} ({}): {e}", image.id, image.name))
    })?;
    Ok((Camera::new(image.name.clone(), intrinsics, pose), undistortion))
}

/// Cross-checks shared by both layouts: unique camera and image ids, every image's camera exists.
/// Then sort images by id.
fn assemble(
    cameras: Located<ColmapCamera>,
    images: Located<ColmapImage>,
    points: Vec<ColmapPoint>,
    cameras_path: &Path,
    images_path: &Path,
) -> Result<ColmapModel, FormatError> {
    let mut camera_ids = HashSet::new();
    for (cam, at) in &cameras {
        if !camera_ids.insert(cam.id) {
            return Err(FormatError::new(
                cameras_path,
                format!("{at}: camera id {} appears twice", cam.id),
            ));
        }
    }
    let mut image_ids = HashSet::new();
    for (img, at) in &images {
        if !image_ids.insert(img.id) {
            return Err(FormatError::new(
                images_path,
                format!("{at}: image id {} appears twice", img.id),
            ));
        }
        if !camera_ids.contains(&img.camera_id) {
            return Err(FormatError::new(
                images_path,
                format!(
                    "{at}: image {} ({}) refers to camera {}, which {} does not contain",
                    img.id,
                    img.name,
                    img.camera_id,
                    cameras_path.display()
                ),
            ));
        }
    }
    let mut images: Vec<ColmapImage> = images.into_iter().map(|(i, _)| i).collect();
    images.sort_by_key(|i| i.id);
    Ok(ColmapModel { cameras: cameras.into_iter().map(|(c, _)| c).collect(), images, points })
}

/// Checks applied to every record while parsing, in both layouts.
/// `what` names the values, made only for the message.
fn check_finite(what: impl FnOnce() -> String, values: &[f64]) -> Result<(), String> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(format!("{} is not finite: {values:?}", what()))
    }
}

fn check_camera(cam: &ColmapCamera) -> Result<(), String> {
    let (_, count) = model_by_name(&cam.model).ok_or_else(|| {
        format!("unknown camera model {:?} (COLMAP knows {})", cam.model, known_models())
    })?;
    if cam.params.len() != count {
        return Err(format!(
            "camera {}: {} takes {count} parameters, found {}",
            cam.id,
            cam.model,
            cam.params.len()
        ));
    }
    check_finite(|| format!("camera {} parameters", cam.id), &cam.params)
}

fn check_image(img: &ColmapImage) -> Result<(), String> {
    check_finite(|| format!("image {} qvec", img.id), &img.qvec)?;
    check_finite(|| format!("image {} tvec", img.id), &img.tvec)?;
    if img.qvec.iter().map(|v| v * v).sum::<f64>() < 1e-24 {
        return Err(format!("image {}: qvec is the zero quaternion", img.id));
    }
    Ok(())
}

/// A COLMAP id stored as a signed 32-bit integer must not be negative.
fn id_u32(v: i32, what: &str) -> Result<u32, String> {
    u32::try_from(v).map_err(|_| format!("{what} is negative ({v})"))
}
