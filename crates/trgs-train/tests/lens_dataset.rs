//! A scene folder whose photos were taken through a distorting lens (the synthetic scene through
//! OPENCV and OPENCV_FISHEYE, as COLMAP would model them) loads as pinhole views: the loader says
//! what it did, the views have the pinhole camera the undistortion chose, the glass masks stay
//! labels, and the views load the same at every thread count and with the photos downscaled.
use trgs_synthetic::{SyntheticConfig, SyntheticLens, generate, write_dataset};
use trgs_train::{LoadOptions, Resolution, TrainingData};

#[test]
fn distorted_photos_load_as_pinhole_views() {
    for lens in [SyntheticLens::Opencv, SyntheticLens::OpencvFisheye] {
        let dir = trgs_core::scratch::ScratchDir::new("lens-dataset");
        let config = SyntheticConfig { lens, ..SyntheticConfig::small() };
        let scene = generate(&config);
        write_dataset(&scene, &dir).expect("write the dataset");
        let data = TrainingData::load(
            &trgs_core::io::SceneFolder::open(&dir).expect("open the dataset"),
            &LoadOptions::at(Resolution::Original),
        )
        .expect("load the dataset");
        let note = data.notes.iter().find(|n| n.contains("camera model")).expect("a lens note");
        assert!(note.contains(lens.colmap_model()), "{note}");
        assert!(note.contains(&format!("on {} views", scene.cameras.len())), "{note}");
        let view = &data.train[0];
        let u = view.undistortion.as_ref().expect("undistorted");
        assert_eq!(u.photo_size(), (64, 48));
        assert_eq!(view.camera.intrinsics, u.pinhole, "the view is the pinhole camera");
        assert_ne!((view.camera.width(), view.camera.height()), (64, 48), "the pinhole is larger");
        assert_eq!((view.image.width, view.image.height), (u.pinhole.width, u.pinhole.height));
        // Masks are resampled by label: only the scene's labels appear, and glass stays glass.
        let masked: Vec<_> = data.train.iter().filter_map(|v| v.mask.as_ref()).collect();
        assert_eq!(masked.len(), config.masked_views);
        for m in masked {
            assert!(m.data.iter().all(|&l| l <= 1));
            assert!(m.data.contains(&1), "the pane is in every masked view");
        }
        // At half the size the photos are downscaled before undistortion.
        let half = TrainingData::load(
            &trgs_core::io::SceneFolder::open(&dir).expect("open the dataset"),
            &LoadOptions::at(Resolution::Downscale(2.0)),
        )
        .expect("load at half size");
        let v = &half.train[0];
        let u = v.undistortion.as_ref().expect("undistorted");
        assert_eq!(u.photo_size(), (32, 24));
        assert_eq!((v.image.width, v.image.height), (v.camera.width(), v.camera.height()));
    }
}
