//! The reflection model's switches, which `compose`, `compose_bwd` and their twins follow.
use crate::plane_math::{schlick, schlick_grad};

/// Which parts of the reflection model are on. The full model has both; each switch off is one
/// of the paper's ablations (section "Reflection intensity and Fresnel-based reflection").
/// A run's metrics.json records it (`reflection_model`); a switch the record leaves out is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct ReflectionModel {
    /// Schlick's view-dependent R_raw; off: R_raw = R0, a learnable constant.
    pub fresnel: bool,
    /// The reflection intensity map A; off: C_r = C_raw.
    pub intensity: bool,
}

impl Default for ReflectionModel {
    fn default() -> Self {
        Self { fresnel: true, intensity: true }
    }
}

impl ReflectionModel {
    /// R_raw at incidence cosine `cos`.
    pub fn strength(self, r0: f64, cos: f64) -> f64 {
        if self.fresnel { schlick(r0, cos) } else { r0 }
    }

    /// dR_raw/dR0 and dR_raw/dcos.
    pub fn strength_grad(self, r0: f64, cos: f64) -> (f64, f64) {
        if self.fresnel { schlick_grad(r0, cos) } else { (1.0, 0.0) }
    }

    /// The intensity a pixel's reflection is scaled by.
    pub fn intensity(self, a: f64) -> f64 {
        if self.intensity { a } else { 1.0 }
    }
}
