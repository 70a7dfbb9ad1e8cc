//! COLMAP's table of camera models: the ids `cameras.bin` stores, the names the text layout and
//! [`crate::lens::colmap_camera_model`] use, and each model's number of parameters.

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
pub(super) fn model_by_id(id: i32) -> Option<(&'static str, usize)> {
    CAMERA_MODELS.iter().find(|m| m.0 == id).map(|m| (m.1, m.2))
}

/// (model id, parameter count) of a model name.
pub(crate) fn model_by_name(name: &str) -> Option<(i32, usize)> {
    CAMERA_MODELS.iter().find(|m| m.1 == name).map(|m| (m.0, m.2))
}

/// The names of every model COLMAP knows, for messages.
pub(super) fn known_models() -> String {
    CAMERA_MODELS.iter().map(|m| m.1).collect::<Vec<_>>().join(", ")
}
