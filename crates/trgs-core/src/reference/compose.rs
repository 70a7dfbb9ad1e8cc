//! Stage `compose`: per pixel, the nearest plane hit by the camera ray (hit mask H), Schlick's
//! R_raw, R = R_raw M, the reflection C_r = C_raw A of the hit plane, and the final
//! C = (1 - R) C_t + R C_r. Pixels that hit no plane show C_t. [`ReflectionModel`] switches
//! Schlick and A off for the ablations.
use crate::image::Image;
use crate::pipeline::ReflectionModel;
use crate::plane_math::{incidence_cos, nearest_plane_hit};
use crate::scene::{Camera, ReflectionPlane};

#[derive(Clone, Debug)]
pub struct ComposeOutput {
    /// H: 0 where no plane is hit, k + 1 where plane k is the nearest hit.
    pub hit: Image<u32>,
    pub strength_raw: Image<f64>,
    pub strength: Image<f64>,
    /// C_r, RGB (zero where no plane is hit).
    pub reflection: Image<f64>,
    pub color: Image<f64>,
}

/// `raw_color[k]` / `intensity[k]` are plane k's pass 2 layers (None when its pass was skipped).
pub fn compose(
    camera: &Camera,
    planes: &[ReflectionPlane],
    transmission: &Image<f64>,
    mask: &Image<f64>,
    raw_color: &[Option<&Image<f64>>],
    intensity: &[Option<&Image<f64>>],
    model: ReflectionModel,
) -> ComposeOutput {
    let (w, h) = (camera.width(), camera.height());
    let mut out = ComposeOutput {
        hit: Image::new(w, h, 1),
        strength_raw: Image::new(w, h, 1),
        strength: Image::new(w, h, 1),
        reflection: Image::new(w, h, 3),
        color: transmission.clone(),
    };
    let origin = camera.pose.centre();
    for y in 0..h {
        for x in 0..w {
            let d = camera.pixel_ray(x, y);
            // Only planes whose mirrored pass ran are in the frame (as in WGSL `compose`).
            let ran = |k: usize| raw_color[k].is_some() && intensity[k].is_some();
            let Some((k, _)) = nearest_plane_hit(planes, ran, origin, d) else { continue };
            let (Some(raw), Some(a)) = (raw_color[k], intensity[k]) else { continue };
            let plane = &planes[k];
            let r_raw = model.strength(plane.r0(), incidence_cos(plane.unit_normal(), d));
            let r = r_raw * mask.get(x, y, 0);
            out.hit.set(x, y, 0, k as u32 + 1);
            out.strength_raw.set(x, y, 0, r_raw);
            out.strength.set(x, y, 0, r);
            for c in 0..3 {
                let cr = raw.get(x, y, c) * model.intensity(a.get(x, y, 0));
                out.reflection.set(x, y, c, cr);
                out.color.set(x, y, c, (1.0 - r) * transmission.get(x, y, c) + r * cr);
            }
        }
    }
    out
}
