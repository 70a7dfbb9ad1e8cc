//! `cameras.json` as the INRIA 3DGS code writes it into its output folder: one entry per view with
//! the camera centre (`position`), the camera-to-world rotation as rows (`rotation`, OpenCV axes:
//! x right, y down, z forward) and the focal lengths in pixels at the image size given. Viewers of
//! INRIA-layout runs (SIBR and others) read this file; trgs writes it into every run folder and its
//! viewer snaps to these views. `cx` and `cy` are trgs additions (the INRIA file assumes a
//! centred principal point, which is also the default when they are missing).
use super::error::read_text;
use super::{FormatError, write_atomic};
use crate::scene::{Camera, Intrinsics, Pose};
use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};
use std::path::Path;

#[derive(Debug, Serialize, Deserialize)]
struct Entry {
    id: usize,
    img_name: String,
    width: u32,
    height: u32,
    position: [f64; 3],
    rotation: [[f64; 3]; 3],
    fy: f64,
    fx: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    cx: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    cy: Option<f64>,
}

/// The JSON text of `cameras`.
pub fn encode_cameras_json(cameras: &[Camera]) -> String {
    let entries: Vec<Entry> = cameras
        .iter()
        .enumerate()
        .map(|(id, c)| {
            let to_world = c.pose.rotation.transpose();
            let row = |r: usize| [to_world.col(0)[r], to_world.col(1)[r], to_world.col(2)[r]];
            let k = &c.intrinsics;
            Entry {
                id,
                img_name: c.name.clone(),
                width: k.width,
                height: k.height,
                position: c.pose.centre().to_array(),
                rotation: [row(0), row(1), row(2)],
                fy: k.fy,
                fx: k.fx,
                cx: Some(k.cx),
                cy: Some(k.cy),
            }
        })
        .collect();
    // Structs of numbers and strings always serialise (a NaN becomes null); an empty list in
    // place of a failure would silently lose every view.
    #[allow(clippy::expect_used)]
    serde_json::to_string_pretty(&entries).expect("camera entries serialise")
}

/// Write `cameras` to `path` (atomically).
pub fn write_cameras_json(path: &Path, cameras: &[Camera]) -> Result<(), FormatError> {
    write_atomic(path, encode_cameras_json(cameras).as_bytes())
}

/// Parse the text of a `cameras.json`; `path` names the file in errors.
pub fn parse_cameras_json(text: &str, path: &Path) -> Result<Vec<Camera>, FormatError> {
    let entries: Vec<Entry> = serde_json::from_str(text).map_err(|e| {
        FormatError::new(
            path,
            format!(
                "{e}; expected a JSON list of {{id, img_name, width, height, position, rotation, \
                 fx, fy}} as the INRIA 3DGS code writes"
            ),
        )
    })?;
    entries
        .into_iter()
        .map(|e| {
            let rows = DMat3::from_cols_array_2d(&e.rotation).transpose();
            let intrinsics = Intrinsics {
                fx: e.fx,
                fy: e.fy,
                cx: e.cx.unwrap_or(0.5 * f64::from(e.width)),
                cy: e.cy.unwrap_or(0.5 * f64::from(e.height)),
                width: e.width,
                height: e.height,
            };
            let camera = Camera::new(
                e.img_name.clone(),
                intrinsics,
                Pose::from_camera_to_world(rows, DVec3::from_array(e.position)),
            );
            camera.validate().map_err(|err| {
                FormatError::new(path, format!("camera {} ({}): {err}", e.id, e.img_name))
            })?;
            Ok(camera)
        })
        .collect()
}

/// Read the views of a `cameras.json`.
pub fn read_cameras_json(path: &Path) -> Result<Vec<Camera>, FormatError> {
    parse_cameras_json(&read_text(path)?, path)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(name: &str, eye: DVec3) -> Camera {
        let mut k = Intrinsics::from_fov_x(1.1, 64, 48);
        k.cx = 30.5;
        Camera::new(name, k, Pose::look_at(eye, DVec3::new(0.1, 0.2, 3.0), DVec3::NEG_Y))
    }

    #[test]
    fn round_trip_keeps_every_camera() {
        let cams = vec![camera("a", DVec3::new(1.0, -0.5, -2.0)), camera("b", DVec3::ZERO)];
        let back = parse_cameras_json(&encode_cameras_json(&cams), Path::new("c.json"))
            .expect("own output parses");
        assert_eq!(back.len(), 2);
        for (a, b) in cams.iter().zip(&back) {
            assert_eq!(a.name, b.name);
            assert_eq!(a.intrinsics, b.intrinsics);
            assert!(a.pose.rotation.abs_diff_eq(b.pose.rotation, 1e-12));
            assert!((a.pose.translation - b.pose.translation).abs().max_element() < 1e-12);
        }
    }

    #[test]
    fn inria_entry_without_principal_point_is_centred() {
        let text = r#"[{"id": 0, "img_name": "00001", "width": 100, "height": 50,
            "position": [1.0, 2.0, 3.0], "rotation": [[1,0,0],[0,1,0],[0,0,1]],
            "fy": 80.0, "fx": 81.0}]"#;
        let cams = parse_cameras_json(text, Path::new("c.json")).expect("INRIA entry parses");
        assert_eq!(cams[0].intrinsics.cx, 50.0);
        assert_eq!(cams[0].intrinsics.cy, 25.0);
        assert!((cams[0].pose.centre() - DVec3::new(1.0, 2.0, 3.0)).length() < 1e-12);
    }

    #[test]
    fn malformed_file_names_the_file_and_the_format() {
        let err = parse_cameras_json("{\"id\": 0}", Path::new("run/cameras.json"))
            .expect_err("an object is not a list of cameras");
        let msg = err.to_string();
        assert!(msg.contains("run/cameras.json") && msg.contains("INRIA"), "{msg}");
        let bad = r#"[{"id": 0, "img_name": "x", "width": 0, "height": 5,
            "position": [0,0,0], "rotation": [[1,0,0],[0,1,0],[0,0,1]], "fy": 1, "fx": 1}]"#;
        let err = parse_cameras_json(bad, Path::new("c.json")).expect_err("zero width");
        assert!(err.to_string().contains("camera 0 (x)"), "{err}");
    }
}
