//! The viewer's camera: an exact [`Pose`] (so that snapping to a dataset view reproduces it bit
//! for bit) moved by orbit, pan, zoom and fly controls. The controls keep the horizon level:
//! after each move the image x axis is rebuilt perpendicular to the world's up direction.
use glam::{DMat3, DQuat, DVec3};
use trgs_core::scene::{Camera, Intrinsics, Pose};

/// Radians of rotation per pixel of mouse drag.
const RADIANS_PER_PIXEL: f64 = 0.005;
/// The steepest look up or down, as |cos| of the angle between the view and the up direction.
const MAX_VERTICAL: f64 = 0.995;

#[derive(Clone, Debug, PartialEq)]
pub struct ViewCamera {
    /// World-to-camera transform (OpenCV axes: x right, y down, z forward).
    pub pose: Pose,
    /// Distance from the eye to the orbit centre along the view direction.
    pub distance: f64,
    /// The world's up direction (unit).
    pub up: DVec3,
    /// Vertical field of view in radians.
    pub fov_y: f64,
    /// Principal point as a fraction of the image size (0.5, 0.5 is centred).
    pub centre: [f64; 2],
}

impl ViewCamera {
    /// Looking at `target` from `eye`.
    pub fn look_at(eye: DVec3, target: DVec3, up: DVec3, fov_y: f64) -> Self {
        let up = up.normalize();
        Self {
            pose: Pose::look_at(eye, target, up),
            distance: (target - eye).length().max(1e-3),
            up,
            fov_y,
            centre: [0.5, 0.5],
        }
    }

    /// Exactly the view of `camera`, orbiting `distance` ahead of it.
    pub fn from_camera(camera: &Camera, up: DVec3, distance: f64) -> Self {
        let k = &camera.intrinsics;
        Self {
            pose: camera.pose,
            distance: distance.max(1e-3),
            up: up.normalize(),
            fov_y: 2.0 * (0.5 * f64::from(k.height) / k.fy).atan(),
            centre: [k.cx / f64::from(k.width), k.cy / f64::from(k.height)],
        }
    }

    pub fn eye(&self) -> DVec3 {
        self.pose.centre()
    }

    /// Camera axes in world space: (right, down, forward).
    pub fn axes(&self) -> (DVec3, DVec3, DVec3) {
        let to_world = self.pose.rotation.transpose();
        (to_world.x_axis, to_world.y_axis, to_world.z_axis)
    }

    pub fn target(&self) -> DVec3 {
        self.eye() + self.axes().2 * self.distance
    }

    /// The camera for an image of `width x height` (square pixels, this field of view).
    pub fn camera(&self, width: u32, height: u32) -> Camera {
        let fy = 0.5 * f64::from(height) / (0.5 * self.fov_y).tan();
        let intrinsics = Intrinsics {
            fx: fy,
            fy,
            cx: self.centre[0] * f64::from(width),
            cy: self.centre[1] * f64::from(height),
            width,
            height,
        };
        Camera::new("viewer", intrinsics, self.pose)
    }

    /// Place the eye at `eye` looking along `forward`, horizon level.
    fn set(&mut self, eye: DVec3, forward: DVec3) {
        let forward = forward.normalize();
        let mut right = (-self.up).cross(forward);
        if right.length_squared() < 1e-12 {
            // Looking straight along the up direction: keep the current right axis.
            right = self.axes().0;
        }
        let right = right.normalize();
        let down = forward.cross(right);
        self.pose = Pose::from_camera_to_world(DMat3::from_cols(right, down, forward), eye);
    }

    /// Turn the view direction by `yaw` about the up direction and `pitch` about the camera's
    /// right axis (positive: towards up), stopping at the steepest allowed look instead of
    /// passing the vertical. A step that would pass it ends at the limit, so the view can always
    /// reach the limit (refusing the whole step would leave it up to one step short).
    fn turned(&self, yaw: f64, pitch: f64) -> DVec3 {
        let (right, _, forward) = self.axes();
        let elevation = forward.dot(self.up).clamp(-1.0, 1.0).asin();
        let steepest = MAX_VERTICAL.asin();
        let target = (elevation + pitch).clamp(-steepest, steepest);
        // The horizontal heading; looking straight along up it comes from the right axis.
        let mut heading = forward - self.up * forward.dot(self.up);
        if heading.length_squared() < 1e-18 {
            heading = self.up.cross(right);
        }
        let heading = heading.normalize();
        let f = heading * target.cos() + self.up * target.sin();
        DQuat::from_axis_angle(self.up, yaw) * f
    }

    /// Orbit about the target by a mouse drag of (dx, dy) pixels.
    pub fn orbit(&mut self, dx: f64, dy: f64) {
        let target = self.target();
        let forward = self.turned(-dx * RADIANS_PER_PIXEL, -dy * RADIANS_PER_PIXEL);
        self.set(target - forward * self.distance, forward);
    }

    /// Turn the head in place by a mouse drag of (dx, dy) pixels (fly mode).
    pub fn look(&mut self, dx: f64, dy: f64) {
        let forward = self.turned(-dx * RADIANS_PER_PIXEL, -dy * RADIANS_PER_PIXEL);
        self.set(self.eye(), forward);
    }

    /// Move eye and target sideways by a drag of (dx, dy) pixels in an image `height` tall.
    pub fn pan(&mut self, dx: f64, dy: f64, height: f64) {
        let (right, down, forward) = self.axes();
        let per_pixel = 2.0 * self.distance * (0.5 * self.fov_y).tan() / height.max(1.0);
        let eye = self.eye() - (right * dx + down * dy) * per_pixel;
        self.set(eye, forward);
    }

    /// Move towards the target by `steps` scroll steps (negative: away); never through it.
    pub fn zoom(&mut self, steps: f64) {
        let target = self.target();
        let forward = self.axes().2;
        self.distance = (self.distance * (-0.1 * steps).exp()).max(1e-3);
        self.set(target - forward * self.distance, forward);
    }

    /// Fly by `local` (right, down, forward) times `step` world units; the target moves along.
    pub fn fly(&mut self, local: DVec3, step: f64) {
        let (right, down, forward) = self.axes();
        let eye = self.eye() + (right * local.x + down * local.y + forward * local.z) * step;
        self.set(eye, forward);
    }
}

/// The world's up direction from a set of views: the mean of their image-up axes, or -y (COLMAP's
/// usual convention) without views.
pub fn up_of(cameras: &[Camera]) -> DVec3 {
    let sum: DVec3 = cameras.iter().map(|c| -(c.pose.rotation.transpose().y_axis)).sum();
    if sum.length() > 1e-6 { sum.normalize() } else { DVec3::NEG_Y }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> ViewCamera {
        ViewCamera::look_at(DVec3::new(0.0, -1.0, -4.0), DVec3::ZERO, DVec3::NEG_Y, 0.9)
    }

    #[test]
    fn orbit_keeps_the_target_and_the_distance() {
        let mut c = cam();
        let (t, d) = (c.target(), c.distance);
        c.orbit(120.0, -40.0);
        assert!((c.target() - t).length() < 1e-9);
        assert!(((c.eye() - t).length() - d).abs() < 1e-9);
        let (right, _, _) = c.axes();
        assert!(right.dot(c.up).abs() < 1e-9, "horizon level");
    }

    #[test]
    fn orbit_never_flips_over_the_pole() {
        let mut c = cam();
        for _ in 0..100 {
            c.orbit(0.0, 50.0);
        }
        assert!(c.axes().2.dot(c.up).abs() <= MAX_VERTICAL + 1e-9);
        assert!(c.pose.rotation.determinant() > 0.999);
    }

    #[test]
    fn pitch_reaches_the_limit_and_turns_back() {
        let mut c = cam();
        // One large step past the vertical ends at the limit, not where it started.
        c.look(0.0, -1000.0);
        let steepest = c.axes().2.dot(c.up);
        assert!((steepest - MAX_VERTICAL).abs() < 1e-9, "{steepest}");
        // A small step down from the limit is taken as asked.
        let before = steepest.asin();
        c.look(0.0, 20.0);
        let after = c.axes().2.dot(c.up).asin();
        assert!((before - after - 20.0 * RADIANS_PER_PIXEL).abs() < 1e-9);
        // The heading did not change on the way.
        let mut level = cam();
        level.look(0.0, 0.0);
        let h = |v: DVec3, up: DVec3| (v - up * v.dot(up)).normalize();
        assert!((h(c.axes().2, c.up) - h(level.axes().2, c.up)).length() < 1e-9);
    }

    #[test]
    fn zoom_and_pan_move_as_asked() {
        let mut c = cam();
        let t = c.target();
        c.zoom(5.0);
        assert!(c.distance < 4.2 * (-0.4f64).exp());
        assert!((c.target() - t).length() < 1e-9);
        let before = c.target();
        c.pan(100.0, 0.0, 400.0);
        let moved = c.target() - before;
        assert!(moved.dot(c.axes().0) < 0.0 && moved.dot(c.axes().1).abs() < 1e-9);
    }

    #[test]
    fn snapping_to_a_camera_reproduces_it() {
        let k = Intrinsics::from_fov_x(1.2, 200, 100);
        let pose = Pose::look_at(DVec3::new(1.0, 0.0, -3.0), DVec3::ZERO, DVec3::NEG_Y);
        let view = Camera::new("v", k, pose);
        let c = ViewCamera::from_camera(&view, DVec3::NEG_Y, 3.0);
        let back = c.camera(200, 100);
        assert_eq!(back.pose, pose);
        assert!((back.intrinsics.fy - k.fy).abs() < 1e-9);
        assert!((back.intrinsics.cx - k.cx).abs() < 1e-9);
    }

    #[test]
    fn up_is_the_mean_image_up() {
        let k = Intrinsics::from_fov_x(1.0, 10, 10);
        let pose = Pose::look_at(DVec3::new(0.0, 0.0, -3.0), DVec3::ZERO, DVec3::Y);
        assert!((up_of(&[Camera::new("a", k, pose)]) - DVec3::Y).length() < 1e-9);
        assert_eq!(up_of(&[]), DVec3::NEG_Y);
    }
}
