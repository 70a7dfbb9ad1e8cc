//! The lens models against OpenCV's own functions: `tests/fixtures/lens_reference.json`, written by
//! `python3 crates/trgs-core/tests/fixtures/lens_reference.py` (opencv-python-headless), holds a
//! grid of photo pixels with their undistorted positions (cv2.undistortPoints,
//! cv2.fisheye.undistortPoints) and a grid of rays with their projections (cv2.projectPoints,
//! cv2.fisheye.projectPoints) for every COLMAP model trgs undistorts.
use serde::Deserialize;
use trgs_core::lens::{Lens, READ_MODELS, Undistortion, colmap_camera_model};

#[derive(Deserialize)]
struct Reference {
    models: Vec<Case>,
}

#[derive(Deserialize)]
struct Case {
    model: String,
    width: u32,
    height: u32,
    params: Vec<f64>,
    pixels: Vec<[f64; 2]>,
    undistorted: Vec<[f64; 2]>,
    rays: Vec<[f64; 2]>,
    projected: Vec<[f64; 2]>,
}

/// The bar for agreement with OpenCV.
const TOLERANCE_PX: f64 = 0.01;

fn reference() -> Reference {
    let text = include_str!("fixtures/lens_reference.json");
    serde_json::from_str(text).expect("lens_reference.json parses")
}

#[test]
fn undistortion_matches_opencv_for_every_model() {
    let cases = reference().models;
    let models: Vec<&str> = cases.iter().map(|c| c.model.as_str()).collect();
    // Every model trgs reads that has a lens (the pinholes have none to undistort).
    for expected in READ_MODELS.into_iter().filter(|m| !m.ends_with("PINHOLE")) {
        assert!(models.contains(&expected), "the fixture lacks {expected}");
    }
    for case in &cases {
        let (k, d) = colmap_camera_model(&case.model, &case.params, case.width, case.height)
            .expect("a supported model");
        let d = d.expect("the fixture's lenses distort");
        let mut worst: f64 = 0.0;
        for (p, want) in case.pixels.iter().zip(&case.undistorted) {
            let (x, y) = d
                .undistort((p[0] - k.cx) / k.fx, (p[1] - k.cy) / k.fy)
                .unwrap_or_else(|| panic!("{}: no inverse at {p:?}", case.model));
            let got = [k.fx * x + k.cx, k.fy * y + k.cy];
            worst = worst.max((got[0] - want[0]).abs()).max((got[1] - want[1]).abs());
        }
        assert!(worst < TOLERANCE_PX, "{}: undistorted {worst} px from OpenCV", case.model);
        println!("{}: undistorted within {worst:.1e} px of OpenCV", case.model);
        let mut worst: f64 = 0.0;
        for (r, want) in case.rays.iter().zip(&case.projected) {
            let (xd, yd) = d.distort(r[0], r[1]);
            let got = [k.fx * xd + k.cx, k.fy * yd + k.cy];
            worst = worst.max((got[0] - want[0]).abs()).max((got[1] - want[1]).abs());
        }
        assert!(worst < TOLERANCE_PX, "{}: projected {worst} px from OpenCV", case.model);
        println!("{}: projected within {worst:.1e} px of OpenCV", case.model);
        // Every fixture lens inverts over its whole photo, so a pinhole view exists.
        let lens = Lens { model: case.model.clone(), intrinsics: k, distortion: d };
        let u = Undistortion::new(lens).expect("the fixture's lenses invert over the photo");
        assert!(u.pinhole.width > 0 && u.pinhole.height > 0);
    }
}

/// A FULL_OPENCV lens whose radial profile rises to 0.92 at normalised radius 1.6, dips and rises
/// again: the photo's corners (radius 1.0) have a preimage only on the far branch (radius 2.6),
/// which cv2.undistortPoints returns without complaint. No pinhole view of such a photo exists,
/// and the loader must say so rather than resample it.
#[test]
fn a_lens_that_folds_inside_the_photo_is_refused() {
    let params = [800.0, 805.0, 640.0, 480.0, 0.12, -0.03, 0.001, -0.002, 0.004, 0.35, 0.02, 0.001];
    let (k, d) = colmap_camera_model("FULL_OPENCV", &params, 1280, 960).expect("parses");
    let lens =
        Lens { model: "FULL_OPENCV".into(), intrinsics: k, distortion: d.expect("distorts") };
    let err = Undistortion::new(lens).expect_err("folds").to_string();
    assert!(err.contains("FULL_OPENCV") && err.contains("1280x960"), "{err}");
}
