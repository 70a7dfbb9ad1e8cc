//! Pinhole cameras in the COLMAP/OpenCV convention: x right, y down, z forward,
//! world-to-camera pose `x_cam = R x_world + t`, pixel centres at +0.5.
use glam::{DMat3, DVec2, DVec3};

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum CameraError {
    #[error("camera intrinsics: {0}")]
    Intrinsics(String),
    #[error("camera pose: {0}")]
    Pose(String),
}

/// PINHOLE intrinsics in pixels for an image of `width x height`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Intrinsics {
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
    pub width: u32,
    pub height: u32,
}

impl Intrinsics {
    /// Intrinsics with a horizontal field of view in radians, square pixels, centred principal point.
    pub fn from_fov_x(fov_x: f64, width: u32, height: u32) -> Self {
        let f = 0.5 * f64::from(width) / (0.5 * fov_x).tan();
        Self {
            fx: f,
            fy: f,
            cx: 0.5 * f64::from(width),
            cy: 0.5 * f64::from(height),
            width,
            height,
        }
    }

    /// The same camera for an image resized to `width x height` (focal lengths and centre scale).
    pub fn resized(&self, width: u32, height: u32) -> Self {
        let sx = f64::from(width) / f64::from(self.width);
        let sy = f64::from(height) / f64::from(self.height);
        Self {
            fx: self.fx * sx,
            fy: self.fy * sy,
            cx: self.cx * sx,
            cy: self.cy * sy,
            width,
            height,
        }
    }

    /// Direction in camera space (not normalised, z = 1) through the continuous pixel position.
    pub fn unproject(&self, px: f64, py: f64) -> DVec3 {
        DVec3::new((px - self.cx) / self.fx, (py - self.cy) / self.fy, 1.0)
    }

    pub fn validate(&self) -> Result<(), CameraError> {
        let finite = [self.fx, self.fy, self.cx, self.cy].iter().all(|v| v.is_finite());
        if !finite {
            return Err(CameraError::Intrinsics(format!("non-finite value in {self:?}")));
        }
        if self.fx <= 0.0 || self.fy <= 0.0 {
            return Err(CameraError::Intrinsics(format!(
                "focal lengths must be positive, got fx = {}, fy = {}",
                self.fx, self.fy
            )));
        }
        if self.width == 0 || self.height == 0 {
            return Err(CameraError::Intrinsics(format!(
                "image size must be positive, got {}x{}",
                self.width, self.height
            )));
        }
        Ok(())
    }
}

/// World-to-camera rigid transform `x_cam = rotation * x_world + translation`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub rotation: DMat3,
    pub translation: DVec3,
}

impl Default for Pose {
    fn default() -> Self {
        Self { rotation: DMat3::IDENTITY, translation: DVec3::ZERO }
    }
}

impl Pose {
    /// From a COLMAP quaternion (w, x, y, z) and translation.
    pub fn from_qvec_tvec(q: [f64; 4], t: [f64; 3]) -> Self {
        let [w, x, y, z] = q;
        let n = (w * w + x * x + y * y + z * z).sqrt();
        let quat = glam::DQuat::from_xyzw(x / n, y / n, z / n, w / n);
        Self { rotation: DMat3::from_quat(quat), translation: DVec3::from_array(t) }
    }

    /// The COLMAP quaternion (w, x, y, z) with w >= 0.
    pub fn qvec(&self) -> [f64; 4] {
        let q = glam::DQuat::from_mat3(&self.rotation).normalize();
        let s = if q.w < 0.0 { -1.0 } else { 1.0 };
        [s * q.w, s * q.x, s * q.y, s * q.z]
    }

    /// A camera at `eye` looking at `target`, with image-up roughly along `up`.
    pub fn look_at(eye: DVec3, target: DVec3, up: DVec3) -> Self {
        let z = (target - eye).normalize();
        // Image y points down (-up); x = y x z points right.
        let x = (-up).cross(z).normalize();
        let y = z.cross(x);
        let rotation = DMat3::from_cols(x, y, z).transpose();
        Self { rotation, translation: -(rotation * eye) }
    }

    /// From a camera-to-world matrix (columns x, y, z axes and centre) in the OpenCV convention.
    pub fn from_camera_to_world(axes: DMat3, centre: DVec3) -> Self {
        let rotation = axes.transpose();
        Self { rotation, translation: -(rotation * centre) }
    }

    /// From a nerfstudio/Blender (OpenGL: y up, z backward) camera-to-world rotation and centre.
    pub fn from_opengl_camera_to_world(axes: DMat3, centre: DVec3) -> Self {
        let flip = DMat3::from_diagonal(DVec3::new(1.0, -1.0, -1.0));
        Self::from_camera_to_world(axes * flip, centre)
    }

    /// The camera centre in world space, `-R^T t`.
    pub fn centre(&self) -> DVec3 {
        -(self.rotation.transpose() * self.translation)
    }

    pub fn transform_point(&self, x: DVec3) -> DVec3 {
        self.rotation * x + self.translation
    }

    /// World-space unit direction of a camera-space direction.
    pub fn direction_to_world(&self, d_cam: DVec3) -> DVec3 {
        (self.rotation.transpose() * d_cam).normalize()
    }

    pub fn validate(&self) -> Result<(), CameraError> {
        let r = self.rotation;
        let finite =
            r.to_cols_array().iter().chain(self.translation.as_ref()).all(|v| v.is_finite());
        if !finite {
            return Err(CameraError::Pose("non-finite value in the world-to-camera pose".into()));
        }
        let err = (r * r.transpose() - DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        if err > 1e-4 || r.determinant() < 0.0 {
            return Err(CameraError::Pose(format!(
                "rotation is not orthonormal with determinant +1 (|R R^T - I| = {err:.2e}, det = {:.4})",
                r.determinant()
            )));
        }
        Ok(())
    }
}

/// A named camera: intrinsics and pose.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub name: String,
    pub intrinsics: Intrinsics,
    pub pose: Pose,
}

impl Camera {
    pub fn new(name: impl Into<String>, intrinsics: Intrinsics, pose: Pose) -> Self {
        Self { name: name.into(), intrinsics, pose }
    }

    pub fn width(&self) -> u32 {
        self.intrinsics.width
    }

    pub fn height(&self) -> u32 {
        self.intrinsics.height
    }

    /// The continuous pixel position of world point `p`, or None when `p` is not in front of
    /// the camera. The position may lie outside the image.
    pub fn project(&self, p: DVec3) -> Option<DVec2> {
        let q = self.pose.transform_point(p);
        if q.z <= 0.0 {
            return None;
        }
        let k = &self.intrinsics;
        Some(DVec2::new(k.fx * q.x / q.z + k.cx, k.fy * q.y / q.z + k.cy))
    }

    /// The pixel position of world point `p` when it is in front of the camera and inside its
    /// image.
    pub fn image_point(&self, p: DVec3) -> Option<DVec2> {
        self.project(p).filter(|&u| self.in_image(u, 0.0))
    }

    /// Whether the camera sees world point `p` directly: in front of it and inside its image.
    pub fn sees(&self, p: DVec3) -> bool {
        self.image_point(p).is_some()
    }

    /// Whether `p` is in front of the camera and inside its image grown by `margin` (a fraction
    /// of the width and height) on every side: what a camera near this one, pointing nearly the
    /// same way, may see.
    pub fn nearly_sees(&self, p: DVec3, margin: f64) -> bool {
        self.project(p).is_some_and(|u| self.in_image(u, margin))
    }

    /// Whether pixel position `u` lies in the image grown by `margin` (a fraction of the width
    /// and height) on every side.
    fn in_image(&self, u: DVec2, margin: f64) -> bool {
        let (w, h) = (f64::from(self.width()), f64::from(self.height()));
        let (mx, my) = (margin * w, margin * h);
        u.x >= -mx && u.y >= -my && u.x < w + mx && u.y < h + my
    }

    /// World-space unit ray direction through the centre of pixel `(x, y)`.
    pub fn pixel_ray(&self, x: u32, y: u32) -> DVec3 {
        let d = self.intrinsics.unproject(f64::from(x) + 0.5, f64::from(y) + 0.5);
        self.pose.direction_to_world(d)
    }

    pub fn validate(&self) -> Result<(), CameraError> {
        self.intrinsics.validate()?;
        self.pose.validate()
    }
}

/// A general world-to-camera affine map `x_cam = linear * x + translation` with the world-space
/// position of its centre. For real cameras `linear` is a rotation; for a camera mirrored about a
/// reflection plane it is `R H` (determinant -1). The centre is kept explicitly so that gradients
/// reach it (the SH view direction of a mirrored pass uses `Hm(c)`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewTransform {
    pub linear: DMat3,
    pub translation: DVec3,
    pub centre: DVec3,
}

impl From<&Pose> for ViewTransform {
    fn from(pose: &Pose) -> Self {
        Self { linear: pose.rotation, translation: pose.translation, centre: pose.centre() }
    }
}

impl ViewTransform {
    pub fn transform_point(&self, x: DVec3) -> DVec3 {
        self.linear * x + self.translation
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn look_at_keeps_up_up_and_right_right() {
        // World up is +y; a camera at z = -5 looking at the origin.
        let pose = Pose::look_at(DVec3::new(0.0, 0.0, -5.0), DVec3::ZERO, DVec3::Y);
        let k = Intrinsics::from_fov_x(1.0, 64, 48);
        let project = |x: DVec3| {
            let p = pose.transform_point(x);
            (k.fx * p.x / p.z + k.cx, k.fy * p.y / p.z + k.cy)
        };
        let (_, v_up) = project(DVec3::new(0.0, 1.0, 0.0));
        assert!(v_up < k.cy, "a point above the target is in the upper half of the image");
        // Looking along +z with +y up, world +x is on the camera's left (right-handed world).
        let (u_left, _) = project(DVec3::new(1.0, 0.0, 0.0));
        assert!(u_left < k.cx);
        assert!((pose.centre() - DVec3::new(0.0, 0.0, -5.0)).length() < 1e-12);
        assert!((pose.rotation.determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn nearly_sees_grows_the_image_by_the_margin_on_every_side() {
        let k = Intrinsics::from_fov_x(1.0, 64, 48);
        let camera =
            Camera::new("c", k, Pose::look_at(DVec3::new(0.0, 0.0, -5.0), DVec3::ZERO, DVec3::Y));
        // A point whose pixel is `du` pixels left of the image's left edge, at depth 5.
        let left_of_image = |du: f64| {
            let u = -du;
            let x = (u - k.cx) / k.fx * 5.0;
            // Camera x is world -x for this pose (see the test above).
            DVec3::new(-x, 0.0, 0.0)
        };
        let inside = left_of_image(-3.0);
        let just_out = left_of_image(3.0);
        let far_out = left_of_image(10.0);
        assert!(camera.sees(inside) && camera.nearly_sees(inside, 0.1));
        assert!(!camera.sees(just_out) && camera.nearly_sees(just_out, 0.1), "6.4 px margin");
        assert!(!camera.nearly_sees(far_out, 0.1));
        assert!(camera.nearly_sees(far_out, 0.2));
        assert!(!camera.nearly_sees(DVec3::new(0.0, 0.0, -10.0), 10.0), "behind the camera");
        assert_eq!(camera.nearly_sees(just_out, 0.0), camera.sees(just_out));
    }
}
