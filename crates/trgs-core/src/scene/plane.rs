//! Rectangular reflection planes (glass panes and mirrors).
use glam::DVec3;

#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum Material {
    #[default]
    Glass,
    Mirror,
}

impl Material {
    /// Initial base reflectance R0: 0.2 for glass, 0.99 for a mirror (1.0 in the paper, kept below
    /// one so that its sigmoid logit is finite).
    pub fn initial_r0(self) -> f64 {
        match self {
            Material::Glass => 0.2,
            Material::Mirror => 0.99,
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PlaneError {
    #[error("plane {index}: {what}")]
    Invalid { index: usize, what: String },
}

/// A learnable rectangle: centre `u_p`, normal `n` (unnormalised, normalised in use), in-plane unit
/// axis `t` along the width, `b = n x t` along the height, size `w x h`, and Schlick base
/// reflectance `R0 = sigmoid(r0_logit)`. The front side is where `(x - u_p) . n > 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReflectionPlane {
    pub centre: DVec3,
    pub normal: DVec3,
    pub axis: DVec3,
    pub width: f64,
    pub height: f64,
    pub r0_logit: f64,
    pub material: Material,
}

impl ReflectionPlane {
    /// A plane with R0 from its material; `axis` is re-orthogonalised against `normal`.
    pub fn new(
        centre: DVec3,
        normal: DVec3,
        axis: DVec3,
        width: f64,
        height: f64,
        material: Material,
    ) -> Self {
        let r0 = material.initial_r0();
        let mut p = Self {
            centre,
            normal,
            axis,
            width,
            height,
            r0_logit: (r0 / (1.0 - r0)).ln(),
            material,
        };
        p.orthogonalise_axis();
        p
    }

    pub fn unit_normal(&self) -> DVec3 {
        self.normal.normalize()
    }

    /// How far this plane lies from `truth`: the angle between their normals in degrees (either
    /// facing) and the distance between their centres as a fraction of `truth`'s diagonal, the
    /// measures of the synthetic scenes' plane bars.
    pub fn error_against(&self, truth: &Self) -> (f64, f64) {
        let cos = self.unit_normal().dot(truth.unit_normal()).abs().min(1.0);
        let diag = truth.width.hypot(truth.height);
        (cos.acos().to_degrees(), self.centre.distance(truth.centre) / diag)
    }

    /// The height direction `b = n x t`.
    pub fn bitangent(&self) -> DVec3 {
        self.unit_normal().cross(self.axis)
    }

    pub fn r0(&self) -> f64 {
        1.0 / (1.0 + (-self.r0_logit).exp())
    }

    /// Set R0, kept within [1e-6, 0.999] so that its logit stays finite.
    pub fn set_r0(&mut self, r0: f64) {
        let r0 = r0.clamp(1e-6, 0.999);
        self.r0_logit = (r0 / (1.0 - r0)).ln();
    }

    /// Signed distance of `x` from the plane; positive on the front side.
    pub fn signed_distance(&self, x: DVec3) -> f64 {
        (x - self.centre).dot(self.unit_normal())
    }

    /// The four corners, counter-clockwise seen from the front.
    pub fn corners(&self) -> [DVec3; 4] {
        let (t, b) = (self.axis * (0.5 * self.width), self.bitangent() * (0.5 * self.height));
        let c = self.centre;
        [c - t - b, c + t - b, c + t + b, c - t + b]
    }

    /// Make `axis` a unit vector orthogonal to the normal (after the normal has moved).
    pub fn orthogonalise_axis(&mut self) {
        let n = self.unit_normal();
        let t = self.axis - n * self.axis.dot(n);
        if t.length_squared() > 1e-24 {
            self.axis = t.normalize();
        } else {
            // The axis became parallel to the normal: pick any perpendicular direction.
            self.axis = n.any_orthonormal_vector();
        }
    }

    /// Reject non-finite parameters, a zero normal and a zero-area rectangle.
    pub fn validate(&self, index: usize) -> Result<(), PlaneError> {
        let bad = |what: String| PlaneError::Invalid { index, what };
        let vals = [
            ("centre", self.centre.to_array().to_vec()),
            ("normal", self.normal.to_array().to_vec()),
            ("axis", self.axis.to_array().to_vec()),
            ("width", vec![self.width]),
            ("height", vec![self.height]),
            ("r0_logit", vec![self.r0_logit]),
        ];
        for (name, v) in vals {
            if v.iter().any(|x| !x.is_finite()) {
                return Err(bad(format!("{name} is not finite: {v:?}")));
            }
        }
        if self.normal.length_squared() < 1e-24 {
            return Err(bad("normal has zero length".into()));
        }
        // The GPU normalises it in f32, where a length above about 1e19 squares to Inf.
        if self.normal.length_squared() > 1e24 {
            return Err(bad(format!(
                "normal length {:e} is too large (at most 1e12; only its direction matters)",
                self.normal.length()
            )));
        }
        if (self.axis.length() - 1.0).abs() > 1e-6 || self.axis.dot(self.unit_normal()).abs() > 1e-6
        {
            return Err(bad("axis must be a unit vector orthogonal to the normal".into()));
        }
        if !(self.width > 0.0 && self.height > 0.0) {
            return Err(bad(format!(
                "zero-area rectangle ({} x {}): width and height must be positive",
                self.width, self.height
            )));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_error_against_the_truth_is_the_normals_angle_and_the_centre_over_the_diagonal() {
        let truth =
            ReflectionPlane::new(DVec3::ZERO, DVec3::Z, DVec3::X, 3.0, 4.0, Material::Glass);
        let turned = DVec3::new(0.0, 2f64.to_radians().sin(), -2f64.to_radians().cos());
        let p = ReflectionPlane {
            centre: DVec3::new(0.1, 0.0, 0.0),
            ..ReflectionPlane::new(DVec3::ZERO, turned, DVec3::X, 1.0, 1.0, Material::Mirror)
        };
        let (angle, centre) = p.error_against(&truth);
        assert!((angle - 2.0).abs() < 1e-9, "either facing: {angle}");
        assert!((centre - 0.02).abs() < 1e-12, "0.1 of a diagonal of 5: {centre}");
    }
}
