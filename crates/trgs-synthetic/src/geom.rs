//! Ray-primitive intersections for the ground-truth tracer.
//!
//! Written here on purpose instead of reusing `plane_math`: the synthetic scene is the independent
//! check of the renderer, so it must not share the renderer's geometry code (a bug there would
//! otherwise be baked into the truth as well).
use glam::DVec3;

/// A ray with a unit direction; hits are reported as distances `t` along it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ray {
    pub origin: DVec3,
    pub dir: DVec3,
}

impl Ray {
    pub fn new(origin: DVec3, dir: DVec3) -> Self {
        Self { origin, dir }
    }

    pub fn at(&self, t: f64) -> DVec3 {
        self.origin + self.dir * t
    }
}

/// Nearest `t > t_min` where the ray meets the sphere (from outside or from inside).
pub(crate) fn ray_sphere(ray: &Ray, centre: DVec3, radius: f64, t_min: f64) -> Option<f64> {
    let oc = ray.origin - centre;
    // |d| = 1, so the quadratic is t^2 + 2 b t + c = 0.
    let b = oc.dot(ray.dir);
    let c = oc.length_squared() - radius * radius;
    let disc = b * b - c;
    if disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    [-b - s, -b + s].into_iter().find(|&t| t > t_min)
}

/// Nearest `t > t_min` where the ray meets the surface of the axis-aligned box, with the outward
/// unit normal of the face it lies on.
pub(crate) fn ray_box(ray: &Ray, min: DVec3, max: DVec3, t_min: f64) -> Option<(f64, DVec3)> {
    let mut t_enter = f64::NEG_INFINITY;
    let mut t_exit = f64::INFINITY;
    let mut enter_axis = 0;
    let mut exit_axis = 0;
    for a in 0..3 {
        let (o, d) = (ray.origin[a], ray.dir[a]);
        if d == 0.0 {
            // Parallel to this slab: either always inside it or never.
            if o < min[a] || o > max[a] {
                return None;
            }
            continue;
        }
        let (mut t0, mut t1) = ((min[a] - o) / d, (max[a] - o) / d);
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        if t0 > t_enter {
            t_enter = t0;
            enter_axis = a;
        }
        if t1 < t_exit {
            t_exit = t1;
            exit_axis = a;
        }
    }
    if t_enter > t_exit {
        return None;
    }
    // The face normal points against the ray when entering and along it when leaving.
    let (t, axis, sign) = if t_enter > t_min {
        (t_enter, enter_axis, -ray.dir[enter_axis].signum())
    } else if t_exit > t_min {
        (t_exit, exit_axis, ray.dir[exit_axis].signum())
    } else {
        return None;
    };
    let mut n = DVec3::ZERO;
    n[axis] = sign;
    Some((t, n))
}

/// A rotation by `degrees` about the vertical (y) line through `pivot`: a pane turned on its
/// centre line and its frame. Positive angles turn +x towards -z.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Turn {
    pub pivot: DVec3,
    cos: f64,
    sin: f64,
}

impl Turn {
    pub fn about_y(pivot: DVec3, degrees: f64) -> Self {
        let (sin, cos) = degrees.to_radians().sin_cos();
        Self { pivot, cos, sin }
    }

    pub fn dir(&self, d: DVec3) -> DVec3 {
        DVec3::new(self.cos * d.x + self.sin * d.z, d.y, -self.sin * d.x + self.cos * d.z)
    }

    pub fn dir_inverse(&self, d: DVec3) -> DVec3 {
        DVec3::new(self.cos * d.x - self.sin * d.z, d.y, self.sin * d.x + self.cos * d.z)
    }

    pub fn point(&self, p: DVec3) -> DVec3 {
        self.pivot + self.dir(p - self.pivot)
    }

    pub fn point_inverse(&self, p: DVec3) -> DVec3 {
        self.pivot + self.dir_inverse(p - self.pivot)
    }
}

/// A rectangle `centre + a u + b v` with `|a| <= half_u`, `|b| <= half_v` (u, v orthonormal).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rect {
    pub centre: DVec3,
    pub u: DVec3,
    pub v: DVec3,
    pub half_u: f64,
    pub half_v: f64,
}

impl Rect {
    /// `u x v`, the side the rectangle calls its front.
    pub fn normal(&self) -> DVec3 {
        self.u.cross(self.v)
    }

    /// Nearest `t > t_min` where the ray meets the rectangle, with the in-plane coordinates
    /// `(a, b)` of the hit (used for textures and for holes).
    pub fn hit(&self, ray: &Ray, t_min: f64) -> Option<(f64, f64, f64)> {
        let n = self.normal();
        let denom = ray.dir.dot(n);
        // A grazing ray sees a zero-width line: treat it as a miss rather than divide by ~0.
        if denom.abs() < 1e-12 {
            return None;
        }
        let t = (self.centre - ray.origin).dot(n) / denom;
        // Written so that a NaN t (ray in the plane) is rejected too.
        if t.is_nan() || t <= t_min {
            return None;
        }
        let r = ray.at(t) - self.centre;
        let (a, b) = (r.dot(self.u), r.dot(self.v));
        (a.abs() <= self.half_u && b.abs() <= self.half_v).then_some((t, a, b))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_from_outside_and_inside() {
        let ray = Ray::new(DVec3::new(0.0, 0.0, -5.0), DVec3::Z);
        let t = ray_sphere(&ray, DVec3::ZERO, 1.0, 1e-9);
        assert!((t.unwrap_or(0.0) - 4.0).abs() < 1e-12);
        let inside = Ray::new(DVec3::ZERO, DVec3::X);
        assert!((ray_sphere(&inside, DVec3::ZERO, 2.0, 1e-9).unwrap_or(0.0) - 2.0).abs() < 1e-12);
        let miss = Ray::new(DVec3::new(0.0, 1.5, -5.0), DVec3::Z);
        assert!(ray_sphere(&miss, DVec3::ZERO, 1.0, 1e-9).is_none());
    }

    #[test]
    fn box_faces_and_parallel_rays() {
        let (lo, hi) = (DVec3::splat(-1.0), DVec3::splat(1.0));
        let ray = Ray::new(DVec3::new(0.2, 0.3, -4.0), DVec3::Z);
        let (t, n) = ray_box(&ray, lo, hi, 1e-9).unwrap_or((0.0, DVec3::ZERO));
        assert!((t - 3.0).abs() < 1e-12 && n == DVec3::NEG_Z);
        let inside = Ray::new(DVec3::ZERO, DVec3::NEG_X);
        let (t, n) = ray_box(&inside, lo, hi, 1e-9).unwrap_or((0.0, DVec3::ZERO));
        assert!((t - 1.0).abs() < 1e-12 && n == DVec3::NEG_X);
        let parallel = Ray::new(DVec3::new(0.0, 2.0, -4.0), DVec3::Z);
        assert!(ray_box(&parallel, lo, hi, 1e-9).is_none());
        // Enters through the -x face at y = 0.5, leaves through +y.
        let oblique = Ray::new(DVec3::new(-3.0, 0.0, 0.0), DVec3::new(1.0, 0.25, 0.0).normalize());
        let (t, n) = ray_box(&oblique, lo, hi, 1e-9).unwrap_or((0.0, DVec3::ZERO));
        assert!((oblique.at(t) - DVec3::new(-1.0, 0.5, 0.0)).length() < 1e-12 && n == DVec3::NEG_X);
    }

    #[test]
    fn turn_round_trips_and_turns_x_towards_minus_z() {
        let turn = Turn::about_y(DVec3::new(1.0, 2.0, 3.0), 90.0);
        let p = DVec3::new(2.0, 5.0, 3.0);
        assert!((turn.point(p) - DVec3::new(1.0, 5.0, 2.0)).length() < 1e-12);
        assert!((turn.point_inverse(turn.point(p)) - p).length() < 1e-12);
        let d = DVec3::new(0.3, -0.4, 0.5);
        assert!((turn.dir_inverse(turn.dir(d)) - d).length() < 1e-12);
    }

    #[test]
    fn rect_hits_inside_only() {
        let rect = Rect { centre: DVec3::ZERO, u: DVec3::X, v: DVec3::Y, half_u: 1.0, half_v: 0.5 };
        let hit = rect.hit(&Ray::new(DVec3::new(0.5, 0.25, 2.0), DVec3::NEG_Z), 1e-9);
        assert_eq!(hit, Some((2.0, 0.5, 0.25)));
        assert!(rect.hit(&Ray::new(DVec3::new(0.5, 0.75, 2.0), DVec3::NEG_Z), 1e-9).is_none());
        assert!(rect.hit(&Ray::new(DVec3::new(0.0, 0.0, 2.0), DVec3::Z), 1e-9).is_none());
    }
}
