//! The settings of a render and the check both renderers apply to them before any work.
use super::ReflectionModel;
use crate::scene::InvalidInput;

/// Settings of the reference renderer (trgs-render's `RenderOptions` has the same three fields
/// among its own).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    /// Gaussians with a camera-space depth below this are culled (0.2 as in 3DGS).
    pub near: f64,
    /// Colour behind the last transmittance of C_t.
    pub background: [f64; 3],
    /// The reflection model's switches (the full model by default).
    pub reflection: ReflectionModel,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self { near: 0.2, background: [0.0; 3], reflection: ReflectionModel::default() }
    }
}

/// Settings no frame can be made with, refused by the twin and the GPU renderer alike: a
/// non-finite background (every pixel would be NaN), a near plane that is not a positive finite
/// depth (at or behind the camera the projection divides by zero or draws what is behind it).
pub fn check_render_settings(background: [f64; 3], near: f64) -> Result<(), InvalidInput> {
    if !background.iter().all(|c| c.is_finite()) {
        let problem = format!("background {background:?} must be finite");
        return Err(InvalidInput::Setting { what: "background", problem });
    }
    if !(near > 0.0 && near.is_finite()) {
        let problem = format!("near {near} must be a positive finite depth");
        return Err(InvalidInput::Setting { what: "near", problem });
    }
    Ok(())
}
