//! The ground-truth ray tracer: opaque Lambertian surfaces plus thin rectangular panes.
//!
//! Everything here lives in the scene's local frame (y up, panes in z = 0 facing +z); the
//! generator maps rays in and cameras, planes and points out. A primary ray that meets pane k
//! from its front side before any opaque surface is composited as in trgs:
//! `C = (1 - R) C_t + R C_r`, `R = R0 + (1 - R0) (1 - cos)^5`, `cos = clamp(-n.d, 0, 1)`, with
//! `C_t` the opaque colour along the same ray (no refraction: the pane is thin) and `C_r` the
//! opaque colour along the mirrored ray. Secondary rays see opaque surfaces only: trgs renders
//! `C_t` and `C_r` from primary Gaussians, which never represent glass, so a recursive truth
//! (glass seen in a reflection) would be something the model cannot express.
use glam::DVec3;

use super::geom::{Ray, Rect, Turn, ray_box, ray_sphere};
use super::texture::Texture;

/// Rays start this far from their origin surface so that they do not hit it again.
const T_MIN: f64 = 1e-7;

/// Colour of a ray that leaves the scene (the rooms are closed, so only through numerical gaps).
const BACKGROUND: DVec3 = DVec3::new(0.5, 0.5, 0.5);

#[derive(Clone, Debug)]
pub(crate) enum Shape {
    Sphere {
        centre: DVec3,
        radius: f64,
    },
    /// An axis-aligned box, or with `turn` a box turned about a vertical line (a turned pane's
    /// frame); `None` keeps the axis-aligned arithmetic exact.
    Cuboid {
        min: DVec3,
        max: DVec3,
        turn: Option<Turn>,
    },
    /// A rectangle with rectangular holes `[a0, a1, b0, b1]` in its own coordinates (windows).
    Quad {
        rect: Rect,
        holes: Vec<[f64; 4]>,
    },
}

#[derive(Clone, Debug)]
pub(crate) struct Object {
    pub shape: Shape,
    pub texture: Texture,
    /// Multiplies the lighting: lets one room be darker than the other.
    pub gain: f64,
}

/// A thin pane: rectangle (front = `rect.normal()`) and base reflectance.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Pane {
    pub rect: Rect,
    pub r0: f64,
}

#[derive(Clone, Debug)]
pub(crate) struct World {
    pub objects: Vec<Object>,
    pub panes: Vec<Pane>,
    /// Directions towards the lights (unit) and their intensities.
    pub lights: Vec<(DVec3, f64)>,
    pub ambient: f64,
    pub seed: u64,
}

/// The nearest opaque surface along a ray.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SurfaceHit {
    pub t: f64,
    pub object: usize,
    /// Unit normal facing the incoming ray (surfaces are two-sided).
    pub normal: DVec3,
    /// Texture coordinates in metres.
    pub uv: DVec3,
}

/// What one primary ray sees.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sample {
    /// Final composite.
    pub colour: DVec3,
    /// The scene without any pane.
    pub transmission: DVec3,
    /// Index of the pane hit from its front side, if it is the nearest hit.
    pub pane: Option<usize>,
    /// Distance to the nearest opaque surface (infinite on a miss); the tests use it to keep
    /// cameras clear of surfaces.
    #[cfg_attr(not(test), allow(dead_code))]
    pub depth: f64,
}

impl World {
    /// The nearest opaque surface along `ray` beyond `T_MIN`.
    pub fn hit_opaque(&self, ray: &Ray) -> Option<SurfaceHit> {
        let mut best: Option<SurfaceHit> = None;
        for (i, obj) in self.objects.iter().enumerate() {
            let t_max = best.map_or(f64::INFINITY, |h| h.t);
            let hit = match &obj.shape {
                Shape::Sphere { centre, radius } => {
                    ray_sphere(ray, *centre, *radius, T_MIN).filter(|&t| t < t_max).map(|t| {
                        let r = ray.at(t) - *centre;
                        // Solid texture relative to the centre: no seam on the sphere.
                        (t, r / *radius, r)
                    })
                }
                Shape::Cuboid { min, max, turn } => {
                    // A turned box is hit in its own frame; rotations keep t.
                    let own = turn.map_or(*ray, |tr| {
                        Ray::new(tr.point_inverse(ray.origin), tr.dir_inverse(ray.dir))
                    });
                    ray_box(&own, *min, *max, T_MIN).filter(|&(t, _)| t < t_max).map(|(t, n)| {
                        let p = own.at(t) - *min;
                        // The two coordinates across the face, in metres from the box corner.
                        let uv = if n.x != 0.0 {
                            DVec3::new(p.z, p.y, 0.0)
                        } else if n.y != 0.0 {
                            DVec3::new(p.x, p.z, 0.0)
                        } else {
                            DVec3::new(p.x, p.y, 0.0)
                        };
                        (t, turn.map_or(n, |tr| tr.dir(n)), uv)
                    })
                }
                Shape::Quad { rect, holes } => rect
                    .hit(ray, T_MIN)
                    .filter(|&(t, a, b)| {
                        t < t_max
                            && !holes.iter().any(|h| a > h[0] && a < h[1] && b > h[2] && b < h[3])
                    })
                    .map(|(t, a, b)| (t, rect.normal(), DVec3::new(a, b, 0.0))),
            };
            if let Some((t, n, uv)) = hit {
                let normal = if n.dot(ray.dir) > 0.0 { -n } else { n };
                best = Some(SurfaceHit { t, object: i, normal, uv });
            }
        }
        best
    }

    /// Lambertian shading of a hit: albedo times ambient plus directional lights, no shadows.
    pub fn shade(&self, hit: &SurfaceHit) -> DVec3 {
        let object = &self.objects[hit.object];
        let albedo = object.texture.albedo(hit.uv, self.seed);
        let direct: f64 = self.lights.iter().map(|(l, i)| i * hit.normal.dot(*l).max(0.0)).sum();
        let light = object.gain * (self.ambient + direct);
        // Surfaces reflect at most what falls on them; a lamp (gain above 1) is brighter than
        // white, which the glass then reflects brightly, and the photo saturates (`sample`).
        (albedo * light).clamp(DVec3::ZERO, DVec3::splat(object.gain.max(1.0)))
    }

    /// Colour seen along `ray` with panes ignored, and the distance to the surface.
    pub fn radiance_opaque(&self, ray: &Ray) -> (DVec3, f64) {
        match self.hit_opaque(ray) {
            Some(hit) => (self.shade(&hit), hit.t),
            None => (BACKGROUND, f64::INFINITY),
        }
    }

    /// The nearest pane hit from its front side before `t_max`: index and distance.
    pub fn hit_pane(&self, ray: &Ray, t_max: f64) -> Option<(usize, f64)> {
        let mut best: Option<(usize, f64)> = None;
        for (k, pane) in self.panes.iter().enumerate() {
            // Seen from behind, a pane is fully transparent (trgs skips the mirrored pass there).
            if (ray.origin - pane.rect.centre).dot(pane.rect.normal()) <= 0.0 {
                continue;
            }
            let limit = best.map_or(t_max, |b| b.1);
            if let Some((t, _, _)) = pane.rect.hit(ray, T_MIN).filter(|h| h.0 < limit) {
                best = Some((k, t));
            }
        }
        best
    }

    /// Trace one primary ray: composite, transmission and which pane (if any) it shows.
    pub fn sample(&self, ray: &Ray) -> Sample {
        let (transmission, depth) = self.radiance_opaque(ray);
        let Some((k, t)) = self.hit_pane(ray, depth) else {
            // A lamp seen directly saturates the photo.
            let colour = transmission.min(DVec3::ONE);
            return Sample { colour, transmission: colour, pane: None, depth };
        };
        let pane = &self.panes[k];
        let n = pane.rect.normal();
        let mirrored = Ray::new(ray.at(t), ray.dir - 2.0 * ray.dir.dot(n) * n);
        let (reflection, _) = self.radiance_opaque(&mirrored);
        let cos = (-n.dot(ray.dir)).clamp(0.0, 1.0);
        let r = pane.r0 + (1.0 - pane.r0) * (1.0 - cos).powi(5);
        let colour = ((1.0 - r) * transmission + r * reflection).min(DVec3::ONE);
        Sample { colour, transmission: transmission.min(DVec3::ONE), pane: Some(k), depth }
    }

    /// Whether the opaque surface point `p` is visible from `eye` (panes are transparent to
    /// feature matching: "SfM" sees through glass).
    pub fn visible(&self, eye: DVec3, p: DVec3) -> bool {
        let to = p - eye;
        let dist = to.length();
        let ray = Ray::new(eye, to / dist);
        self.hit_opaque(&ray).is_none_or(|h| h.t >= dist * (1.0 - 1e-7) - 1e-9)
    }
}
