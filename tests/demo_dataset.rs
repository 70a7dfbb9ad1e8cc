//! Cross-crate: the built-in synthetic scene written as a scene folder loads back through the
//! dataset reader exactly (cameras, images to 8 bits, masks, split, plane materials), and the
//! truth plane is recoverable from the sparse points near the glass by the plane fitter.
use trgs::core::Material;
use trgs::core::fit::fit_rectangle;
use trgs::core::io::SceneFolder;
use trgs::core::rng::Rng;
use trgs::synthetic::{SyntheticConfig, generate, write_dataset};

#[test]
fn synthetic_scene_round_trips_through_a_scene_folder() {
    let config = SyntheticConfig::small();
    let scene = generate(&config);
    let dir = trgs::core::scratch::ScratchDir::new("demo-dataset");
    write_dataset(&scene, &dir).expect("write dataset");
    let folder = SceneFolder::open(&dir).expect("open dataset");
    assert_eq!(folder.views.len(), scene.cameras.len());
    assert_eq!(folder.test_views, scene.test_views);
    for (i, view) in folder.views.iter().enumerate() {
        let truth = &scene.cameras[i];
        assert_eq!(view.camera.name, truth.name);
        assert_eq!(view.camera.intrinsics, truth.intrinsics);
        let dr = (view.camera.pose.rotation - truth.pose.rotation).to_cols_array();
        assert!(dr.iter().all(|v| v.abs() < 1e-9), "pose of {}", truth.name);
        assert!((view.camera.pose.translation - truth.pose.translation).length() < 1e-9);
        let img = folder.load_image(i).expect("image");
        assert_eq!(img.data, scene.images[i].to_u8(), "image {}", truth.name);
        let mask = folder.load_mask(i).expect("mask").map(|m| m.labels);
        assert_eq!(mask, scene.masks[i], "mask of {}", truth.name);
    }
    assert_eq!(folder.plane_specs.len(), 1);
    assert_eq!(folder.plane_specs[0].material, Material::Glass);
    assert!(folder.plane_specs[0].plane.is_none(), "the input must not leak the truth geometry");
    assert!(folder.points.len() > 100);
}

#[test]
fn truth_plane_is_recoverable_from_points_on_the_frame() {
    let scene = generate(&SyntheticConfig::small());
    let truth = scene.planes[0];
    // Sparse points within 5 cm of the pane's plane and near its rectangle (the frame).
    let near: Vec<glam::DVec3> = scene
        .points
        .iter()
        .map(|(p, _)| glam::DVec3::from_array(*p))
        .filter(|&p| {
            let local = p - truth.centre;
            truth.signed_distance(p).abs() < 0.05
                && local.dot(truth.axis).abs() < 0.5 * truth.width + 0.15
                && local.dot(truth.bitangent()).abs() < 0.5 * truth.height + 0.15
        })
        .collect();
    assert!(near.len() >= 10, "too few frame points: {}", near.len());
    let fit = fit_rectangle(&near, 0.01, 500, &mut Rng::new(1)).expect("fit");
    let angle = fit.normal.dot(truth.unit_normal()).abs().clamp(0.0, 1.0).acos().to_degrees();
    println!("{} frame points, normal error {angle:.3} deg", near.len());
    assert!(angle < 2.0, "normal off by {angle} degrees");
}
