//! File formats. Every reader names the file and what was expected when input is malformed;
//! every writer writes a temporary file and renames it into place.
//!
//! - [`colmap`]: COLMAP sparse models (binary and text);
//! - [`transforms`]: nerfstudio/Blender `transforms.json`;
//! - [`png`]: photos (PNG, or JPEG read strictly by `jpeg`), 8-bit RGB and gray PNG images;
//! - [`masks`]: glass masks (`glass_masks/<image>.png`, label k > 0 = plane k);
//! - [`test_split`]: `test_views.txt` and the default every-8th split;
//! - [`planes_json`]: `planes.json` (plane annotations and trained planes);
//! - [`ply`]: INRIA-layout 3DGS PLY with trgs's extra properties;
//! - [`glb`]: binary glTF with `KHR_gaussian_splatting`, planes as nodes;
//! - [`model`]: a trained model to render (a PLY and its planes.json, a run folder, or a .glb);
//! - [`cameras_json`]: the INRIA output folder's `cameras.json` (a run's views);
//! - [`metrics`]: what is read back of a run's `metrics.json`;
//! - [`run_folder`]: whether the run in a training run's folder has finished;
//! - [`dataset`]: a scene folder that puts the above together.
mod bytes;
pub mod cameras_json;
pub mod colmap;
pub mod dataset;
mod error;
pub mod glb;
mod jpeg;
mod mask_labels;
pub mod masks;
pub mod metrics;
pub mod model;
mod model_values;
pub mod planes_json;
pub mod ply;
pub mod png;
pub mod run_folder;
pub mod spz;
pub mod test_split;
#[cfg(test)]
mod test_util;
pub mod transforms;

pub use cameras_json::{
    encode_cameras_json, parse_cameras_json, read_cameras_json, write_cameras_json,
};
pub use colmap::{ColmapCamera, ColmapImage, ColmapModel, ColmapPoint};
pub use dataset::{SceneFolder, Split, ViewSpec, colmap_dir, view_output_stem};
pub use error::{FormatError, remove_stale_temporaries, write_atomic, write_atomic_with};
pub use glb::{encode_glb, parse_glb, read_glb, write_glb};
pub use masks::{
    GlassMask, MAX_PLANES, check_plane_count, mask_path, read_glass_mask, write_glass_mask,
};
pub use metrics::{CandidateOutline, EvaluationPoint, RunMetrics, ViewScore};
pub use model::{Model, find_ply, load_model};
pub use planes_json::{PlaneSpec, read_planes_json, write_plane_materials, write_planes_json};
pub use ply::{ColouredPoint, encode_ply, parse_ply, read_ply, read_point_cloud_ply, write_ply};
pub use png::{
    read_rgb_image, read_rgb8_image, write_jpeg_rgb, write_png_gray, write_png_rgb, write_png_rgb8,
};
pub use run_folder::{
    UNFINISHED_RUN_MARKER, UnfinishedRun, check_finished_run, clear_unfinished_run,
    read_unfinished_run, write_unfinished_run,
};
pub use spz::{encode_spz, parse_spz, read_spz, write_spz};
pub use test_split::{default_test_views, read_test_views, write_test_views};
pub use transforms::{TransformsFrame, read_transforms, write_transforms};
