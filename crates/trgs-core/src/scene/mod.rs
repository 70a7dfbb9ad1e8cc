//! The scene model: Gaussians, cameras and reflection planes, and the validation that keeps
//! non-finite or degenerate input out of every renderer.
mod attribute;
mod camera;
mod gaussians;
mod plane;
mod validate;

pub use attribute::{Attribute, PerAttribute, attribute_widths};
pub use camera::{Camera, CameraError, Intrinsics, Pose, ViewTransform};
pub use gaussians::{Gaussians, Population, Scalar, sh_coeff_count};
pub use plane::{Material, PlaneError, ReflectionPlane};
pub use validate::{InvalidInput, validate_gaussians, validate_planes, validate_scene};
