//! nerfstudio / Blender `transforms.json`: intrinsics given globally or per frame (`fl_x, fl_y,
//! cx, cy, w, h`, or Blender's `camera_angle_x`), and per frame an image path and an OpenGL
//! camera-to-world matrix (x right, y up, z backward), converted to trgs's COLMAP convention.
//! Lens distortion as nerfstudio writes it: `camera_model` OPENCV with `k1, k2, k3, p1, p2`, or
//! OPENCV_FISHEYE with `k1..k4`; such frames are undistorted into pinhole views on load.
use std::path::{Path, PathBuf};

use glam::{DMat3, DVec3};
use serde_json::{Map, Value, json};

use super::error::read_text;
use super::png::image_dimensions;
use super::{FormatError, write_atomic};
use crate::lens::{Distortion, Lens, Undistortion};
use crate::scene::{Camera, Intrinsics, Pose};

/// One frame: its camera (named by the image's file name) and the image file. With lens
/// distortion the camera is the pinhole view the photo is undistorted into.
#[derive(Clone, Debug, PartialEq)]
pub struct TransformsFrame {
    pub camera: Camera,
    pub image_path: PathBuf,
    pub undistortion: Option<Undistortion>,
}

/// Read every frame, in file order. Image paths are relative to the JSON's folder; a path without
/// extension (Blender's `./train/r_0`) is tried as given, then with `.png`. A path that exists in
/// neither form is returned as given, for the caller to report, unless its size is needed.
pub fn read_transforms(path: &Path) -> Result<Vec<TransformsFrame>, FormatError> {
    let text = read_text(path)?;
    let root: Value =
        serde_json::from_str(&text).map_err(|e| FormatError::new(path, e.to_string()))?;
    let fail = |m: String| FormatError::new(path, m);
    let global =
        root.as_object().ok_or_else(|| fail("expected a JSON object at the top level".into()))?;
    let frames = global
        .get("frames")
        .ok_or_else(|| fail("missing field `frames`".into()))?
        .as_array()
        .ok_or_else(|| fail("`frames` must be an array".into()))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    // Frames usually share one lens: its undistortion (a sweep of the photo's border) is made once.
    let mut last: Option<Undistortion> = None;
    let mut out = frames
        .iter()
        .enumerate()
        .map(|(i, frame)| {
            read_frame(global, frame, dir, &mut last).map_err(|m| fail(format!("frames[{i}]: {m}")))
        })
        .collect::<Result<Vec<_>, _>>()?;
    name_by_relative_path_if_needed(&mut out, dir);
    Ok(out)
}

/// The sparse point cloud a transforms.json names (nerfstudio's `ply_file_path`, relative to its
/// folder, in the frames' coordinates), if any.
pub fn transforms_point_cloud(path: &Path) -> Result<Option<PathBuf>, FormatError> {
    let text = read_text(path)?;
    let root: Value =
        serde_json::from_str(&text).map_err(|e| FormatError::new(path, e.to_string()))?;
    match root.get("ply_file_path").filter(|v| !v.is_null()) {
        None => Ok(None),
        Some(Value::String(p)) => Ok(Some(path.parent().unwrap_or(Path::new(".")).join(p))),
        Some(other) => {
            Err(FormatError::new(path, format!("`ply_file_path` must be a string, found {other}")))
        }
    }
}

/// Views are named by their image's file name, as COLMAP names them, unless two share one (the
/// Blender scenes' `train/r_0` and `test/r_0` in one merged file): then every view is named by
/// its image's path relative to the JSON's folder (`train/r_0.png`), which masks, the test split
/// and the outputs use in the same way.
pub(crate) fn name_by_relative_path_if_needed(frames: &mut [TransformsFrame], dir: &Path) {
    let mut names: Vec<&str> = frames.iter().map(|f| f.camera.name.as_str()).collect();
    names.sort_unstable();
    if names.windows(2).all(|w| w[0] != w[1]) {
        return;
    }
    for f in frames {
        let rel = f.image_path.strip_prefix(dir).unwrap_or(&f.image_path);
        let parts = super::dataset::plain_components(rel);
        if !parts.is_empty() {
            f.camera.name = parts.join("/");
        }
    }
}

fn read_frame(
    global: &Map<String, Value>,
    frame: &Value,
    dir: &Path,
    last: &mut Option<Undistortion>,
) -> Result<TransformsFrame, String> {
    let frame = frame.as_object().ok_or("expected a JSON object")?;
    // A per-frame value overrides the global one (nerfstudio's rule).
    let get = |key: &str| frame.get(key).or_else(|| global.get(key)).filter(|v| !v.is_null());
    let num = |key: &str| -> Result<Option<f64>, String> {
        match get(key) {
            None => Ok(None),
            Some(v) => match v.as_f64() {
                Some(x) if x.is_finite() => Ok(Some(x)),
                _ => Err(format!("`{key}` must be a finite number, found {v}")),
            },
        }
    };
    let coefficient = |key: &str| num(key).map(|v| v.unwrap_or(0.0));
    let [k1, k2, k3, k4, p1, p2] = ["k1", "k2", "k3", "k4", "p1", "p2"].map(coefficient);
    let (k1, k2, k3, k4, p1, p2) = (k1?, k2?, k3?, k4?, p1?, p2?);
    let distortion = match camera_model(get("camera_model"))? {
        LensKind::Perspective => {
            if k4 != 0.0 {
                return Err(format!(
                    "`k4` = {k4} with a perspective camera: nerfstudio's r^8 radial term has no \
                     COLMAP or OpenCV model; undistort the images first"
                ));
            }
            Distortion::RadialTangential { k: [k1, k2, k3, 0.0, 0.0, 0.0], p: [p1, p2] }
        }
        LensKind::Fisheye => {
            if p1 != 0.0 || p2 != 0.0 {
                return Err(
                    "OPENCV_FISHEYE has no tangential terms: `p1` and `p2` must be 0".into()
                );
            }
            Distortion::Fisheye { k: [k1, k2, k3, k4] }
        }
    };

    let file_path = get("file_path")
        .ok_or("missing field `file_path`")?
        .as_str()
        .ok_or("`file_path` must be a string")?;
    let image_path = resolve_image(dir, file_path);
    let name = image_path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .ok_or_else(|| format!("`file_path` {file_path:?} does not name a file"))?;

    let (width, height) = match (num("w")?, num("h")?) {
        (Some(w), Some(h)) => (size(w, "w")?, size(h, "h")?),
        (None, None) => image_dimensions(&image_path).map_err(|e| {
            format!("`w` and `h` are not given, and the image size cannot be read ({e}); add \"w\" and \"h\"")
        })?,
        _ => return Err("give both `w` and `h`, or neither".into()),
    };
    let (w, h) = (f64::from(width), f64::from(height));
    let fx = match (num("fl_x")?, num("camera_angle_x")?) {
        (Some(f), _) => f,
        (None, Some(angle)) => 0.5 * w / (0.5 * angle).tan(),
        (None, None) => return Err("no focal length: expected `fl_x` or `camera_angle_x`".into()),
    };
    let fy = match (num("fl_y")?, num("camera_angle_y")?) {
        (Some(f), _) => f,
        (None, Some(angle)) => 0.5 * h / (0.5 * angle).tan(),
        (None, None) => fx,
    };
    let cx = num("cx")?.unwrap_or(0.5 * w);
    let cy = num("cy")?.unwrap_or(0.5 * h);
    let intrinsics = Intrinsics { fx, fy, cx, cy, width, height };
    intrinsics.validate().map_err(|e| e.to_string())?;
    let undistortion = if distortion.is_identity() {
        None
    } else {
        let model = match distortion {
            Distortion::Fisheye { .. } => "OPENCV_FISHEYE",
            Distortion::RadialTangential { .. } => "OPENCV",
        };
        let lens = Lens { model: model.into(), intrinsics, distortion };
        match last.as_ref().filter(|u| u.lens == lens) {
            Some(same) => Some(same.clone()),
            None => {
                let made = Undistortion::new(lens).map_err(|e| e.to_string())?;
                *last = Some(made.clone());
                Some(made)
            }
        }
    };
    let pinhole = undistortion.as_ref().map_or(intrinsics, |u| u.pinhole);

    let matrix = frame.get("transform_matrix").ok_or("missing field `transform_matrix`")?;
    let (axes, centre) = read_matrix(matrix)?;
    let camera = Camera::new(name, pinhole, Pose::from_opengl_camera_to_world(axes, centre));
    camera.validate().map_err(|e| e.to_string())?;
    Ok(TransformsFrame { camera, image_path, undistortion })
}

/// The lens family of nerfstudio's `camera_model`.
enum LensKind {
    Perspective,
    Fisheye,
}

fn camera_model(model: Option<&Value>) -> Result<LensKind, String> {
    match model.map(|m| m.as_str().ok_or(format!("`camera_model` must be a string, found {m}"))) {
        None | Some(Ok("OPENCV" | "PINHOLE" | "SIMPLE_PINHOLE")) => Ok(LensKind::Perspective),
        Some(Ok("OPENCV_FISHEYE")) => Ok(LensKind::Fisheye),
        Some(Ok(other)) => Err(format!(
            "camera_model {other:?} is not supported; trgs reads PINHOLE, OPENCV (k1, k2, k3, p1, \
             p2) and OPENCV_FISHEYE (k1..k4): undistort the images first"
        )),
        Some(Err(m)) => Err(m),
    }
}

fn size(v: f64, key: &str) -> Result<u32, String> {
    if v >= 1.0 && v.fract() == 0.0 && v <= f64::from(u32::MAX) {
        Ok(v as u32)
    } else {
        Err(format!("`{key}` = {v} is not a positive whole number of pixels"))
    }
}

fn resolve_image(dir: &Path, file_path: &str) -> PathBuf {
    let given = dir.join(file_path);
    if given.is_file() {
        return given;
    }
    let png = dir.join(format!("{file_path}.png"));
    if png.is_file() { png } else { given }
}

/// A 4x4 (or 3x4) row-major camera-to-world matrix: rotation columns and centre.
fn read_matrix(v: &Value) -> Result<(DMat3, DVec3), String> {
    let bad = || format!("`transform_matrix` must be 4 rows of 4 finite numbers, found {v}");
    let rows = v.as_array().filter(|r| r.len() == 3 || r.len() == 4).ok_or_else(bad)?;
    let mut m = [[0.0; 4]; 3];
    for (r, row) in rows.iter().take(3).enumerate() {
        let row = row.as_array().filter(|r| r.len() == 4).ok_or_else(bad)?;
        for (c, x) in row.iter().enumerate() {
            m[r][c] = x.as_f64().filter(|x| x.is_finite()).ok_or_else(bad)?;
        }
    }
    let col = |c: usize| DVec3::new(m[0][c], m[1][c], m[2][c]);
    Ok((DMat3::from_cols(col(0), col(1), col(2)), col(3)))
}

/// Write frames with per-frame intrinsics and OpenGL camera-to-world matrices; image paths are
/// written relative to the JSON's folder when they lie inside it.
pub fn write_transforms(path: &Path, frames: &[TransformsFrame]) -> Result<(), FormatError> {
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut out = Vec::with_capacity(frames.len());
    for (i, f) in frames.iter().enumerate() {
        let rel = f.image_path.strip_prefix(dir).unwrap_or(&f.image_path);
        let file_path = rel.to_str().ok_or_else(|| {
            FormatError::new(
                path,
                format!("frames[{i}]: the image path {} is not UTF-8", f.image_path.display()),
            )
        })?;
        // A distorted frame is written as its photo's own camera and lens.
        let k = f.undistortion.as_ref().map_or(&f.camera.intrinsics, |u| &u.lens.intrinsics);
        let pose = &f.camera.pose;
        let flip = DMat3::from_diagonal(DVec3::new(1.0, -1.0, -1.0));
        let axes = pose.rotation.transpose() * flip;
        let c = pose.centre();
        let row = |r: usize| json!([axes.x_axis[r], axes.y_axis[r], axes.z_axis[r], c[r]]);
        let mut frame = json!({
            "file_path": file_path,
            "fl_x": k.fx, "fl_y": k.fy, "cx": k.cx, "cy": k.cy, "w": k.width, "h": k.height,
            "transform_matrix": [row(0), row(1), row(2), [0.0, 0.0, 0.0, 1.0]],
        });
        if let (Some(u), Some(fields)) = (&f.undistortion, frame.as_object_mut()) {
            lens_fields(&u.lens.distortion, fields).map_err(|m| {
                FormatError::new(path, format!("frames[{i}] ({}): {m}", f.camera.name))
            })?;
        }
        out.push(frame);
    }
    let text = serde_json::to_string_pretty(&json!({ "frames": out }))
        .map_err(|e| FormatError::new(path, e.to_string()))?;
    write_atomic(path, format!("{text}\n").as_bytes())
}

/// nerfstudio's keys for a distortion; a lens it has no keys for is an error.
fn lens_fields(d: &Distortion, out: &mut Map<String, Value>) -> Result<(), String> {
    let (model, values) = match *d {
        Distortion::RadialTangential { k, p } => {
            if k[3..].iter().any(|&v| v != 0.0) {
                return Err("a rational (FULL_OPENCV) lens has no transforms.json form".into());
            }
            ("OPENCV", vec![("k1", k[0]), ("k2", k[1]), ("k3", k[2]), ("p1", p[0]), ("p2", p[1])])
        }
        Distortion::Fisheye { k } => {
            ("OPENCV_FISHEYE", vec![("k1", k[0]), ("k2", k[1]), ("k3", k[2]), ("k4", k[3])])
        }
    };
    out.insert("camera_model".into(), json!(model));
    for (key, v) in values {
        out.insert(key.into(), json!(v));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::Image;
    use crate::io::test_util::{assert_mentions, scratch_dir};

    fn write(dir: &Path, json: &str) -> PathBuf {
        let path = dir.join("transforms.json");
        std::fs::write(&path, json).expect("write");
        path
    }

    const IDENTITY: &str = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";

    #[test]
    fn round_trip_through_write() {
        let dir = scratch_dir("tf-rt");
        let pose = Pose::look_at(DVec3::new(1.0, 2.0, 3.0), DVec3::new(0.0, 0.5, 0.0), DVec3::Y);
        let cam = Camera::new(
            "a.png",
            Intrinsics { fx: 40.0, fy: 41.0, cx: 15.5, cy: 12.0, width: 32, height: 24 },
            pose,
        );
        let frames = vec![TransformsFrame {
            camera: cam.clone(),
            image_path: dir.join("images/a.png"),
            undistortion: None,
        }];
        let path = dir.join("transforms.json");
        write_transforms(&path, &frames).expect("write");
        assert!(std::fs::read_to_string(&path).expect("read").contains("\"images/a.png\""));
        let back = read_transforms(&path).expect("read");
        assert_eq!(back[0].image_path, dir.join("images/a.png"));
        assert_eq!(
            (back[0].camera.name.as_str(), back[0].camera.intrinsics),
            ("a.png", cam.intrinsics)
        );
        let (a, b) = (back[0].camera.pose, cam.pose);
        assert!((a.rotation - b.rotation).abs().to_cols_array().iter().all(|d| *d < 1e-12));
        assert!((a.translation - b.translation).length() < 1e-12);
    }

    #[test]
    fn blender_angle_and_size_from_png() {
        let dir = scratch_dir("tf-blender");
        crate::io::write_png_rgb(&dir.join("train/r_0.png"), &Image::new(8, 6, 3)).expect("png");
        // Blender: the camera looks down -z; identity c2w means it looks along world -z.
        let json = format!(
            r#"{{"camera_angle_x": 0.9, "frames": [{{"file_path": "./train/r_0", "transform_matrix": {IDENTITY}}}]}}"#
        );
        let frames = read_transforms(&write(&dir, &json)).expect("read");
        let cam = &frames[0].camera;
        assert_eq!(cam.name, "r_0.png");
        assert_eq!((cam.width(), cam.height()), (8, 6));
        assert!((cam.intrinsics.fx - 4.0 / 0.45f64.tan()).abs() < 1e-12);
        assert_eq!(
            (cam.intrinsics.fy, cam.intrinsics.cx, cam.intrinsics.cy),
            (cam.intrinsics.fx, 4.0, 3.0)
        );
        let forward = cam.pose.direction_to_world(DVec3::Z);
        assert!((forward - DVec3::NEG_Z).length() < 1e-12, "camera looks along {forward}");
    }

    #[test]
    fn missing_fields_are_named() {
        let dir = scratch_dir("tf-missing");
        let path =
            write(&dir, r#"{"fl_x": 10, "w": 4, "h": 4, "frames": [{"file_path": "a.png"}]}"#);
        assert_mentions(
            &read_transforms(&path).expect_err("no matrix"),
            &["transforms.json", "frames[0]", "`transform_matrix`"],
        );
        let json = format!(
            r#"{{"w": 4, "h": 4, "frames": [{{"file_path": "a.png", "transform_matrix": {IDENTITY}}}]}}"#
        );
        let path = write(&dir, &json);
        assert_mentions(
            &read_transforms(&path).expect_err("no focal"),
            &["transforms.json", "frames[0]", "fl_x", "camera_angle_x"],
        );
        let path = write(&dir, r#"{"camera_angle_x": 1}"#);
        assert_mentions(
            &read_transforms(&path).expect_err("no frames"),
            &["transforms.json", "`frames`"],
        );
        let path = write(&dir, "{\n\"frames\": [,]}");
        assert_mentions(
            &read_transforms(&path).expect_err("syntax"),
            &["transforms.json", "line 2"],
        );
        let json = r#"{"fl_x": 10, "w": 4, "h": 4, "frames": [{"file_path": "a.png", "transform_matrix": [[1,0,0],[0,1,0]]}]}"#;
        assert_mentions(
            &read_transforms(&write(&dir, json)).expect_err("3x2"),
            &["transforms.json", "4 rows of 4"],
        );
    }

    #[test]
    fn lens_distortion_is_read_and_written_back() {
        let dir = scratch_dir("tf-dist");
        let frame =
            format!(r#""frames": [{{"file_path": "a.png", "transform_matrix": {IDENTITY}}}]"#);
        let json =
            format!(r#"{{"fl_x": 100, "w": 160, "h": 120, "k1": -0.05, "p2": 0.001, {frame}}}"#);
        let frames = read_transforms(&write(&dir, &json)).expect("OPENCV lens");
        let u = frames[0].undistortion.as_ref().expect("undistorted");
        assert_eq!(
            u.lens.distortion,
            Distortion::RadialTangential { k: [-0.05, 0.0, 0.0, 0.0, 0.0, 0.0], p: [0.0, 0.001] }
        );
        assert_eq!(frames[0].camera.intrinsics, u.pinhole, "the view is the pinhole");
        // Written back as the photo's own camera and lens, it reads the same.
        let path = dir.join("back.json");
        write_transforms(&path, &frames).expect("write");
        assert_eq!(read_transforms(&path).expect("read back")[0].undistortion.as_ref(), Some(u));

        let json = format!(
            r#"{{"fl_x": 100, "w": 160, "h": 120, "camera_model": "OPENCV_FISHEYE", "k1": 0.03, {frame}}}"#
        );
        let frames = read_transforms(&write(&dir, &json)).expect("fisheye");
        assert!(matches!(
            frames[0].undistortion.as_ref().map(|u| u.lens.distortion),
            Some(Distortion::Fisheye { .. })
        ));
        let json = format!(
            r#"{{"fl_x": 100, "w": 160, "h": 120, "camera_model": "OPENCV", "k4": 0.01, {frame}}}"#
        );
        assert_mentions(
            &read_transforms(&write(&dir, &json)).expect_err("r^8 term"),
            &["transforms.json", "`k4` = 0.01", "undistort"],
        );
        let json = format!(
            r#"{{"fl_x": 100, "w": 160, "h": 120, "camera_model": "EQUIRECTANGULAR", {frame}}}"#
        );
        assert_mentions(
            &read_transforms(&write(&dir, &json)).expect_err("equirectangular"),
            &["transforms.json", "EQUIRECTANGULAR", "OPENCV_FISHEYE", "undistort"],
        );
        let json = format!(
            r#"{{"fl_x": 10, "w": 4, "h": 4, "camera_model": "OPENCV", "k1": 0, "p2": 0.0, {frame}}}"#
        );
        let frames = read_transforms(&write(&dir, &json)).expect("pinhole");
        assert!(frames[0].undistortion.is_none(), "OPENCV with zero distortion is a pinhole");
    }

    #[test]
    fn unreadable_image_without_size_asks_for_w_and_h() {
        let dir = scratch_dir("tf-jpeg");
        std::fs::write(
            dir.join("a.jpg"),
            [0xff, 0xd8, 0xff, 0xe0, 0, 16, b'J', b'F', b'I', b'F', 0],
        )
        .expect("jpg");
        let json = format!(
            r#"{{"fl_x": 10, "frames": [{{"file_path": "a.jpg", "transform_matrix": {IDENTITY}}}]}}"#
        );
        let err = read_transforms(&write(&dir, &json)).expect_err("jpeg");
        assert_mentions(
            &err,
            &["transforms.json", "frames[0]", "a.jpg", "image header", "add \"w\" and \"h\""],
        );
    }

    #[test]
    fn scaled_matrix_is_refused() {
        let dir = scratch_dir("tf-scale");
        let json = r#"{"fl_x": 10, "w": 4, "h": 4, "frames": [{"file_path": "a.png", "transform_matrix": [[2,0,0,0],[0,2,0,0],[0,0,2,0],[0,0,0,1]]}]}"#;
        assert_mentions(
            &read_transforms(&write(&dir, json)).expect_err("scaled"),
            &["transforms.json", "frames[0]", "orthonormal"],
        );
    }
}
