//! Input validation shared by every renderer: non-finite values and malformed sets are rejected
//! before any work starts, with the attribute and index named.
use super::{Camera, CameraError, Gaussians, PlaneError, ReflectionPlane, Scalar};

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum InvalidInput {
    #[error("Gaussian {index}: {attribute} is not finite ({value})")]
    NonFinite { attribute: &'static str, index: usize, value: f64 },
    #[error("Gaussians: {0}")]
    Layout(String),
    #[error("Gaussian {index}: {attribute} {value} is out of range ({expected})")]
    OutOfRange { attribute: &'static str, index: usize, value: f64, expected: &'static str },
    #[error(transparent)]
    Plane(#[from] PlaneError),
    #[error(transparent)]
    Camera(#[from] CameraError),
    /// A render setting the frame cannot be made with (as the GPU renderer refuses it).
    #[error("render setting {what}: {problem}")]
    Setting { what: &'static str, problem: String },
}

fn check<F: Scalar, const N: usize>(
    attribute: &'static str,
    values: &[[F; N]],
    per: usize,
) -> Result<(), InvalidInput> {
    for (k, v) in values.iter().enumerate() {
        for &x in v {
            let x = x.to_f64();
            if !x.is_finite() {
                return Err(InvalidInput::NonFinite { attribute, index: k / per.max(1), value: x });
            }
        }
    }
    Ok(())
}

/// Validate Gaussians, planes and a camera together.
pub fn validate_scene<F: Scalar>(
    gaussians: &Gaussians<F>,
    planes: &[ReflectionPlane],
    camera: &Camera,
) -> Result<(), InvalidInput> {
    validate_gaussians(gaussians)?;
    validate_planes(planes)?;
    camera.validate()?;
    Ok(())
}

/// The largest log reflection intensity a scene may hold (e^30 = 1e13).
pub const MAX_LOG_REFLECTION: f64 = 30.0;

/// Lengths consistent, every attribute finite, no zero quaternion, reflection intensities that
/// f32 can carry through compose.
pub fn validate_gaussians<F: Scalar>(gaussians: &Gaussians<F>) -> Result<(), InvalidInput> {
    gaussians.check_lengths().map_err(InvalidInput::Layout)?;
    check("mean", &gaussians.means, 1)?;
    check("rotation", &gaussians.rotations, 1)?;
    check("log_scale", &gaussians.log_scales, 1)?;
    let wrap = |v: &[F]| v.iter().map(|&x| [x]).collect::<Vec<_>>();
    check("opacity_logit", &wrap(&gaussians.opacity_logits), 1)?;
    check("sh", &gaussians.sh, gaussians.sh_coeffs())?;
    check("mask_logit", &wrap(&gaussians.mask_logits), 1)?;
    check("log_reflection", &wrap(&gaussians.log_reflections), 1)?;
    // exp(log_reflection) scales the reflection: above e^MAX_LOG_REFLECTION it would overflow
    // f32 in compose (C_r = Inf on the GPU) long before any trained value gets near it.
    if let Some((i, &v)) =
        gaussians.log_reflections.iter().enumerate().find(|(_, v)| v.to_f64() > MAX_LOG_REFLECTION)
    {
        return Err(InvalidInput::OutOfRange {
            attribute: "log_reflection",
            index: i,
            value: v.to_f64(),
            expected: "at most 30",
        });
    }
    for (i, q) in gaussians.rotations.iter().enumerate() {
        let n2: f64 = q.iter().map(|v| v.to_f64() * v.to_f64()).sum();
        if n2 < 1e-24 {
            return Err(InvalidInput::NonFinite {
                attribute: "rotation (zero quaternion)",
                index: i,
                value: n2,
            });
        }
    }
    Ok(())
}

/// Every plane finite, with a non-zero normal and area.
pub fn validate_planes(planes: &[ReflectionPlane]) -> Result<(), InvalidInput> {
    for (k, p) in planes.iter().enumerate() {
        p.validate(k)?;
    }
    Ok(())
}
