//! COLMAP sparse models (`cameras`, `images`, `points3D`) in COLMAP's binary and text layouts,
//! and the conversion of one registered image into a trgs [`Camera`].
//!
//! The readers check what the rest of trgs relies on (parameter counts, finite poses, camera
//! references, unique ids) so that a bad model fails here, naming the file and the record or line,
//! rather than as a NaN deep inside training.
mod binary;
#[cfg(test)]
mod tests;
mod text;

use std::collections::HashSet;
use std::path::Path;

use super::FormatError;
use crate::scene::{Camera, Intrinsics, Pose};

/// COLMAP's camera models as (model id, name, number of parameters), from COLMAP's
/// `sensor/models.h`. The ids are what `cameras.bin` stores.
const CAMERA_MODELS: [(i32, &str, usize); 11] = [
    (0, "SIMPLE_PINHOLE", 3),
    (1, "PINHOLE", 4),
    (2, "SIMPLE_RADIAL", 4),
    (3, "RADIAL", 5),
    (4, "OPENCV", 8),
    (5, "OPENCV_FISHEYE", 8),
    (6, "FULL_OPENCV", 12),
    (7, "FOV", 5),
    (8, "SIMPLE_RADIAL_FISHEYE", 4),
    (9, "RADIAL_FISHEYE", 5),
    (10, "THIN_PRISM_FISHEYE", 12),
];

/// (name, parameter count) of a model id.
fn model_by_id(id: i32) -> Option<(&'static str, usize)> {
    CAMERA_MODELS.iter().find(|m| m.0 == id).map(|m| (m.1, m.2))
}

/// (model id, parameter count) of a model name.
fn model_by_name(name: &str) -> Option<(i32, usize)> {
    CAMERA_MODELS.iter().find(|m| m.1 == name).map(|m| (m.0, m.2))
}

fn known_models() -> String {
    CAMERA_MODELS.iter().map(|m| m.1).collect::<Vec<_>>().join(", ")
}

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

/// A parsed record and where it came from ("record 3", "line 17"), for later cross-checks.
type Located<T> = Vec<(T, String)>;

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

    /// The trgs camera of an image (named by the image's name). Only PINHOLE and SIMPLE_PINHOLE
    /// are supported: every other model has lens distortion, which the splatting rasteriser cannot
    /// model, so the error says to undistort first. The model does not remember its folder, so the
    /// error's path is `cameras`; [`super::SceneFolder`] replaces it with the real file.
    pub fn camera(&self, image: &ColmapImage) -> Result<Camera, FormatError> {
        let fail = |problem: String| FormatError::new("cameras", problem);
        let cam = self.cameras.iter().find(|c| c.id == image.camera_id).ok_or_else(|| {
            fail(format!(
                "image {} ({}) uses camera {}, which does not exist",
                image.id, image.name, image.camera_id
            ))
        })?;
        let (fx, fy, cx, cy) = match (cam.model.as_str(), cam.params.as_slice()) {
            ("PINHOLE", &[fx, fy, cx, cy]) => (fx, fy, cx, cy),
            ("SIMPLE_PINHOLE", &[f, cx, cy]) => (f, f, cx, cy),
            // Lens models whose distortion is exactly zero are pinholes (some pipelines write
            // them after undistorting); the transforms.json reader accepts the same.
            ("SIMPLE_RADIAL", &[f, cx, cy, 0.0]) | ("RADIAL", &[f, cx, cy, 0.0, 0.0]) => {
                (f, f, cx, cy)
            }
            ("OPENCV", &[fx, fy, cx, cy, ref d @ ..])
                if d.len() == 4 && d.iter().all(|&v| v == 0.0) =>
            {
                (fx, fy, cx, cy)
            }
            ("PINHOLE" | "SIMPLE_PINHOLE", p) => {
                return Err(fail(format!(
                    "camera {}: {} needs its parameters, found {}",
                    cam.id,
                    cam.model,
                    p.len()
                )));
            }
            (other, _) => {
                return Err(fail(format!(
                    "camera {} uses the COLMAP model {other} with lens distortion (or the wrong \
                     number of parameters); trgs supports PINHOLE and SIMPLE_PINHOLE (and lens \
                     models whose distortion is zero): undistort the images first (e.g. with \
                     `colmap image_undistorter`) and use the undistorted model",
                    cam.id
                )));
            }
        };
        let size = |v: u64, what: &str| {
            u32::try_from(v)
                .map_err(|_| fail(format!("camera {}: {what} {v} is too large", cam.id)))
        };
        let intrinsics = Intrinsics {
            fx,
            fy,
            cx,
            cy,
            width: size(cam.width, "width")?,
            height: size(cam.height, "height")?,
        };
        intrinsics.validate().map_err(|e| fail(format!("camera {}: {e}", cam.id)))?;
        let pose = Pose::from_qvec_tvec(image.qvec, image.tvec);
        pose.validate().map_err(|e| fail(format!("image {} ({}): {e}", image.id, image.name)))?;
        Ok(Camera::new(image.name.clone(), intrinsics, pose))
    }
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
fn check_finite(what: &str, values: &[f64]) -> Result<(), String> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(format!("{what} is not finite: {values:?}"))
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
    check_finite(&format!("camera {} parameters", cam.id), &cam.params)
}

fn check_image(img: &ColmapImage) -> Result<(), String> {
    check_finite(&format!("image {} qvec", img.id), &img.qvec)?;
    check_finite(&format!("image {} tvec", img.id), &img.tvec)?;
    if img.qvec.iter().map(|v| v * v).sum::<f64>() < 1e-24 {
        return Err(format!("image {}: qvec is the zero quaternion", img.id));
    }
    Ok(())
}

/// A COLMAP id stored as a signed 32-bit integer must not be negative.
fn id_u32(v: i32, what: &str) -> Result<u32, String> {
    u32::try_from(v).map_err(|_| format!("{what} is negative ({v})"))
}
