//! Adjoint of `compose`: from dL/dC and the direct gradients of C_r, R and R_raw to dL/dC_t,
//! dL/dM, each plane's dL/dC_raw^k and dL/dA^k, and each plane's R0 and unit-normal gradients
//! (through Schlick's cosine). H is discrete and passes no gradient.
use super::frame::{Frame, FrameGrads};
use crate::image::Image;
use crate::pipeline::ReflectionModel;
use crate::plane_math::incidence_cos;
use crate::scene::{Camera, ReflectionPlane};
use glam::DVec3;

#[derive(Clone, Debug)]
pub struct ComposeGrads {
    pub transmission: Image<f64>,
    pub mask: Image<f64>,
    /// Per plane (dL/dC_raw, dL/dA).
    pub planes: Vec<(Image<f64>, Image<f64>)>,
    /// Per plane dL/dR0 (not the logit).
    pub r0: Vec<f64>,
    /// Per plane dL/d(unit normal).
    pub unit_normal: Vec<DVec3>,
}

pub fn compose_bwd(
    camera: &Camera,
    planes: &[ReflectionPlane],
    f: &Frame,
    g: &FrameGrads,
    model: ReflectionModel,
) -> ComposeGrads {
    let (w, h) = (f.width(), f.height());
    let mut out = ComposeGrads {
        transmission: g.transmission.clone(),
        mask: g.mask.clone(),
        planes: g.planes.iter().map(|p| (p.raw_color.clone(), p.intensity.clone())).collect(),
        r0: vec![0.0; planes.len()],
        unit_normal: vec![DVec3::ZERO; planes.len()],
    };
    for y in 0..h {
        for x in 0..w {
            let hit = f.hit.get(x, y, 0);
            if hit == 0 {
                for c in 0..3 {
                    let i = out.transmission.index(x, y, c);
                    out.transmission.data[i] += g.color.get(x, y, c);
                }
                continue;
            }
            let k = hit as usize - 1;
            let Some(layers) = f.planes[k].as_ref() else { continue };
            let plane = &planes[k];
            let (r, r_raw, m) =
                (f.strength.get(x, y, 0), f.strength_raw.get(x, y, 0), f.mask.get(x, y, 0));
            let a = model.intensity(layers.intensity.get(x, y, 0));
            let mut g_r = g.strength.get(x, y, 0);
            let mut g_a = 0.0;
            for c in 0..3 {
                let gc = g.color.get(x, y, c);
                let (ct, cr) = (f.transmission.get(x, y, c), f.reflection.get(x, y, c));
                let i = out.transmission.index(x, y, c);
                out.transmission.data[i] += (1.0 - r) * gc;
                g_r += (cr - ct) * gc;
                let g_cr = g.reflection.get(x, y, c) + r * gc;
                let raw = layers.raw_color.get(x, y, c);
                let j = out.planes[k].0.index(x, y, c);
                out.planes[k].0.data[j] += g_cr * a;
                g_a += g_cr * raw;
            }
            if model.intensity {
                let j = out.planes[k].1.index(x, y, 0);
                out.planes[k].1.data[j] += g_a;
            }
            let g_raw = g.strength_raw.get(x, y, 0) + g_r * m;
            let i = out.mask.index(x, y, 0);
            out.mask.data[i] += g_r * r_raw;
            let d = camera.pixel_ray(x, y);
            let n = plane.unit_normal();
            let cos = incidence_cos(n, d);
            let (d_r0, d_cos) = model.strength_grad(plane.r0(), cos);
            out.r0[k] += g_raw * d_r0;
            let dot = -n.dot(d);
            // Inside the clamp, cos = -n . d.
            if model.fresnel && dot > 0.0 && dot < 1.0 {
                out.unit_normal[k] += g_raw * d_cos * (-d);
            }
        }
    }
    out
}
