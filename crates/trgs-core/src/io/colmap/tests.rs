use super::*;
use crate::io::test_util::{assert_mentions, scratch_dir};

fn sample_model() -> ColmapModel {
    let cameras = vec![
        ColmapCamera {
            id: 2,
            model: "PINHOLE".into(),
            width: 64,
            height: 48,
            params: vec![50.0, 51.5, 32.0, 24.0],
        },
        ColmapCamera {
            id: 1,
            model: "SIMPLE_PINHOLE".into(),
            width: 32,
            height: 32,
            params: vec![0.1 + 0.2, 16.0, 16.0],
        },
        ColmapCamera {
            id: 7,
            model: "OPENCV".into(),
            width: 10,
            height: 10,
            params: vec![5.0, 5.0, 5.0, 5.0, 0.01, -0.02, 1e-9, 0.0],
        },
    ];
    let images = vec![
        ColmapImage {
            id: 3,
            qvec: [0.9, 0.1, -0.2, 0.3],
            tvec: [1.0 / 3.0, -2.0, 1e-12],
            camera_id: 2,
            name: "b dir/frame 3.png".into(),
            points2d: vec![([1.5, 2.25], 0), ([3.0, 4.0], -1)],
        },
        ColmapImage {
            id: 1,
            qvec: [1.0, 0.0, 0.0, 0.0],
            tvec: [0.0, 0.0, 0.0],
            camera_id: 1,
            name: "a.png".into(),
            points2d: vec![],
        },
        ColmapImage {
            id: 9,
            qvec: [0.0, 1.0, 0.0, 0.0],
            tvec: [1.0, 2.0, 3.0],
            camera_id: 7,
            name: "c.jpg".into(),
            points2d: vec![],
        },
    ];
    let points = vec![
        ColmapPoint {
            id: 5,
            xyz: [0.1, 0.2, 0.3],
            rgb: [255, 0, 7],
            error: 0.5,
            track: vec![(3, 0), (1, 4)],
        },
        ColmapPoint { id: 2, xyz: [-1e10, 3.5, 0.0], rgb: [1, 2, 3], error: 0.0, track: vec![] },
    ];
    ColmapModel { cameras, images, points }
}

#[test]
fn binary_and_text_of_one_model_load_identically() {
    let model = sample_model();
    let (bin, txt) = (scratch_dir("colmap-bin"), scratch_dir("colmap-txt"));
    model.write_binary(&bin).expect("write bin");
    model.write_text(&txt).expect("write txt");
    let a = ColmapModel::read(&bin).expect("read bin");
    let b = ColmapModel::read(&txt).expect("read txt");
    assert_eq!(a, b);
    // Images come back sorted by id; cameras and points keep their order.
    let ids: Vec<u32> = a.images.iter().map(|i| i.id).collect();
    assert_eq!(ids, [1, 3, 9]);
    let mut expected = model.clone();
    expected.images.sort_by_key(|i| i.id);
    assert_eq!(a, expected);
}

#[test]
fn camera_of_pinhole_and_simple_pinhole() {
    let model = sample_model();
    let (cam, lens) = model.camera(&model.images[0]).expect("pinhole");
    assert!(lens.is_none(), "a pinhole needs no undistortion");
    assert_eq!(cam.name, "b dir/frame 3.png");
    assert_eq!((cam.intrinsics.fx, cam.intrinsics.fy, cam.intrinsics.cx), (50.0, 51.5, 32.0));
    assert_eq!((cam.width(), cam.height()), (64, 48));
    let (cam, _) = model.camera(&model.images[1]).expect("simple pinhole");
    assert_eq!(cam.intrinsics.fx, cam.intrinsics.fy);
}

#[test]
fn distorted_camera_model_is_undistorted_into_a_pinhole() {
    let model = sample_model();
    let (cam, lens) = model.camera(&model.images[2]).expect("OPENCV is undistorted");
    let lens = lens.expect("a distorting lens");
    assert_eq!(lens.lens.model, "OPENCV");
    assert_eq!(lens.photo_size(), (10, 10));
    assert_eq!(cam.intrinsics, lens.pinhole, "the view is the pinhole camera");
    // `views` makes the same cameras, each COLMAP camera's undistortion once.
    let views = model.views().expect("views");
    assert_eq!(views[2], (cam, Some(lens)));
}

#[test]
fn unsupported_or_folding_lenses_are_named() {
    let mut model = sample_model();
    model.cameras[2].model = "THIN_PRISM_FISHEYE".into();
    model.cameras[2].params = vec![5.0, 5.0, 5.0, 5.0, 0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let err = model.camera(&model.images[2]).expect_err("unsupported");
    assert_mentions(&err, &["camera 7", "THIN_PRISM_FISHEYE", "OPENCV_FISHEYE", "undistort"]);
    model.cameras[2].model = "RADIAL".into();
    model.cameras[2].params = vec![2.0, 5.0, 5.0, -0.5, 0.0];
    let err = model.camera(&model.images[2]).expect_err("folds");
    assert_mentions(&err, &["camera 7", "RADIAL", "10x10"]);
}

#[test]
fn lens_models_with_zero_distortion_are_pinholes() {
    let mut model = sample_model();
    let cases: [(&str, Vec<f64>, [f64; 4]); 3] = [
        ("SIMPLE_RADIAL", vec![6.0, 5.0, 4.0, 0.0], [6.0, 6.0, 5.0, 4.0]),
        ("RADIAL", vec![6.0, 5.0, 4.0, 0.0, 0.0], [6.0, 6.0, 5.0, 4.0]),
        ("OPENCV", vec![6.0, 7.0, 5.0, 4.0, 0.0, 0.0, 0.0, 0.0], [6.0, 7.0, 5.0, 4.0]),
    ];
    for (name, params, want) in cases {
        model.cameras[2].model = name.into();
        model.cameras[2].params = params.clone();
        let (cam, lens) = model.camera(&model.images[2]).expect(name);
        let k = cam.intrinsics;
        assert_eq!([k.fx, k.fy, k.cx, k.cy], want, "{name}");
        assert!(lens.is_none(), "{name} without distortion is a pinhole");
        // Any distortion at all is undistorted.
        let mut distorted = params;
        *distorted.last_mut().expect("a coefficient") = 1e-6;
        model.cameras[2].params = distorted;
        let (_, lens) = model.camera(&model.images[2]).expect(name);
        assert!(lens.is_some(), "{name} with distortion");
    }
}

#[test]
fn missing_folder_names_both_layouts() {
    let dir = scratch_dir("colmap-none");
    let err = ColmapModel::read(&dir).expect_err("empty folder");
    assert_mentions(&err, &[&dir.display().to_string(), "cameras.bin", "cameras.txt"]);
}

#[test]
fn truncated_binary_names_file_and_record() {
    let dir = scratch_dir("colmap-trunc");
    sample_model().write_binary(&dir).expect("write");
    let path = dir.join("images.bin");
    let bytes = std::fs::read(&path).expect("read");
    for cut in [3, 20, bytes.len() - 5] {
        std::fs::write(&path, &bytes[..cut]).expect("write");
        let err = ColmapModel::read(&dir).expect_err("truncated");
        assert_mentions(&err, &["images.bin", "truncated"]);
    }
    std::fs::write(&path, &bytes[..bytes.len() - 5]).expect("write");
    let err = ColmapModel::read(&dir).expect_err("truncated");
    assert_mentions(&err, &["image record 2 (of 3)", "points2D"]);
}

#[test]
fn wrong_binary_count_is_an_error() {
    let dir = scratch_dir("colmap-count");
    sample_model().write_binary(&dir).expect("write");
    let path = dir.join("points3D.bin");
    let mut bytes = std::fs::read(&path).expect("read");
    bytes[..8].copy_from_slice(&1u64.to_le_bytes());
    std::fs::write(&path, &bytes).expect("write");
    let err = ColmapModel::read(&dir).expect_err("count too small");
    assert_mentions(&err, &["points3D.bin", "wrong count"]);
    bytes[..8].copy_from_slice(&u64::MAX.to_le_bytes());
    std::fs::write(&path, &bytes).expect("write");
    let err = ColmapModel::read(&dir).expect_err("count too large");
    assert_mentions(&err, &["points3D.bin", "point record 2", "truncated"]);
}

#[test]
fn unknown_model_id_is_an_error() {
    let dir = scratch_dir("colmap-model-id");
    sample_model().write_binary(&dir).expect("write");
    let path = dir.join("cameras.bin");
    let mut bytes = std::fs::read(&path).expect("read");
    bytes[12..16].copy_from_slice(&42i32.to_le_bytes());
    std::fs::write(&path, &bytes).expect("write");
    let err = ColmapModel::read(&dir).expect_err("model 42");
    assert_mentions(&err, &["cameras.bin", "camera record 0", "unknown camera model id 42"]);
}

#[test]
fn non_utf8_name_and_nan_pose_are_errors() {
    let dir = scratch_dir("colmap-utf8");
    let mut model = sample_model();
    model.images.truncate(1);
    model.images[0].name = "ab".into();
    model.write_binary(&dir).expect("write");
    let path = dir.join("images.bin");
    let mut bytes = std::fs::read(&path).expect("read");
    let at = bytes.windows(2).position(|w| w == b"ab").expect("name");
    bytes[at] = 0xff;
    std::fs::write(&path, &bytes).expect("write");
    let err = ColmapModel::read(&dir).expect_err("non-UTF-8");
    assert_mentions(&err, &["images.bin", "image record 0", "UTF-8"]);

    model.images[0].tvec[1] = f64::NAN;
    model.write_binary(&dir).expect("write");
    let err = ColmapModel::read(&dir).expect_err("NaN");
    assert_mentions(&err, &["images.bin", "image record 0", "tvec is not finite"]);
    model.write_text(&dir).expect("write");
    let err = ColmapModel::read_text(&dir).expect_err("NaN");
    assert_mentions(&err, &["images.txt", "line 5", "tvec is not finite"]);
}

#[test]
fn wrong_param_count_in_text_names_line() {
    let dir = scratch_dir("colmap-params");
    sample_model().write_text(&dir).expect("write");
    let path = dir.join("cameras.txt");
    let text = std::fs::read_to_string(&path).expect("read").replace("50 51.5 32 24", "50 51.5 32");
    std::fs::write(&path, text).expect("write");
    let err = ColmapModel::read(&dir).expect_err("3 params for PINHOLE");
    assert_mentions(&err, &["cameras.txt", "line 4", "PINHOLE takes 4 parameters, found 3"]);
}

#[test]
fn bad_text_fields_name_line_and_field() {
    let dir = scratch_dir("colmap-fields");
    sample_model().write_text(&dir).expect("write");
    let path = dir.join("points3D.txt");
    std::fs::write(&path, "# c\n\n5 0.1 0.2 zero 1 2 3 0.5\n").expect("write");
    let err = ColmapModel::read(&dir).expect_err("bad Z");
    assert_mentions(&err, &["points3D.txt", "line 3", "Z", "\"zero\""]);
    std::fs::write(&path, "5 0.1 0.2 0.3 1 2 300 0.5\n").expect("write");
    let err = ColmapModel::read(&dir).expect_err("B = 300");
    assert_mentions(&err, &["points3D.txt", "line 1", "B"]);
}

#[test]
fn missing_camera_reference_is_an_error() {
    let dir = scratch_dir("colmap-ref");
    let mut model = sample_model();
    model.images[1].camera_id = 4;
    model.write_binary(&dir).expect("write");
    let err = ColmapModel::read(&dir).expect_err("camera 4");
    assert_mentions(&err, &["images.bin", "image record 1", "refers to camera 4"]);
    model.write_text(&dir).expect("write");
    let err = ColmapModel::read_text(&dir).expect_err("camera 4");
    assert_mentions(&err, &["images.txt", "line 7", "refers to camera 4"]);
    let err = model.camera(&model.images[1]).expect_err("camera 4");
    assert_mentions(&err, &["camera 4", "does not exist"]);
}
