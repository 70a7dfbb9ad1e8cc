//! The backward pipeline of one view: compose_bwd -> rasterize_bwd (pass 1) -> project_bwd of the
//! real view; per plane: rasterize_reflection_bwd -> project_bwd of the mirrored view -> the chain
//! from the mirrored view `W' = W Hm` to the plane's centre and normal; the normal's
//! normalisation and R0's sigmoid last.
use super::compose_bwd::compose_bwd;
use super::frame::{Frame, FrameGrads};
use super::project_bwd::project_bwd;
use super::rasterize_bwd::{RasterizeUpstream, rasterize_bwd};
use super::rasterize_reflection_bwd::rasterize_reflection_bwd;
use crate::pipeline::{RenderSettings, TileGrid};
use crate::plane_grad::{PlaneGrad, mirrored_view_bwd, plane_grad};
use crate::scene::{Camera, Gaussians, InvalidInput, ReflectionPlane, validate_scene};
use glam::DVec3;

/// Switches of the backward pass that the training stages need.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BackwardOptions {
    /// Stage 2: no gradient from the mirrored passes (C_r) into any Gaussian; the planes' centre
    /// and normal still learn from them through the mirrored view.
    pub block_reflection_to_gaussians: bool,
}

/// Gradients of every parameter: Gaussians (same layout as the scene) and planes.
#[derive(Clone, Debug)]
pub struct SceneGrads {
    pub gaussians: Gaussians<f64>,
    pub planes: Vec<PlaneGrad>,
}

/// Gradients of a scalar loss given dL/d(each layer of `frame`), which `render` produced from the
/// same scene, planes, camera and settings.
pub fn backward(
    g: &Gaussians<f64>,
    planes: &[ReflectionPlane],
    camera: &Camera,
    settings: &RenderSettings,
    frame: &Frame,
    grads: &FrameGrads,
    options: &BackwardOptions,
) -> Result<SceneGrads, InvalidInput> {
    validate_scene(g, planes, camera)?;
    let k = &camera.intrinsics;
    let grid = TileGrid::new(k.width, k.height);
    let mut out = Gaussians::<f64>::zeros(g.len(), g.sh_degree);
    out.populations = g.populations.clone();
    let cg = compose_bwd(camera, planes, frame, grads, settings.reflection);

    let pass = &frame.primary;
    let up = RasterizeUpstream {
        transmission: &cg.transmission,
        depth: &grads.depth,
        depth_variance: &grads.depth_variance,
        mask: &cg.mask,
        alpha: &grads.alpha,
    };
    let pg = rasterize_bwd(
        &pass.projected,
        &pass.values,
        &pass.ranges,
        &grid,
        &frame.pixels,
        &frame.depth,
        settings.background,
        up,
    );
    project_bwd(g, &pass.view, k, &pass.projected, &pg, Some(&mut out));

    let mut plane_grads = Vec::with_capacity(planes.len());
    for (kp, plane) in planes.iter().enumerate() {
        let mut g_u = DVec3::ZERO;
        let mut g_n = cg.unit_normal[kp];
        if let Some(layers) = frame.planes[kp].as_ref() {
            let mp = &layers.pass;
            let (g_raw, g_int) = &cg.planes[kp];
            let rpg = rasterize_reflection_bwd(
                &mp.projected,
                &mp.values,
                &mp.ranges,
                &grid,
                &layers.footprint,
                &layers.pixels,
                g_raw,
                g_int,
            );
            let target = if options.block_reflection_to_gaussians { None } else { Some(&mut out) };
            let vg = project_bwd(g, &mp.view, k, &mp.projected, &rpg, target);
            let (du, dn) = mirrored_view_bwd(plane, &pass.view, &vg);
            g_u += du;
            g_n += dn;
        }
        plane_grads.push(plane_grad(plane, g_u, g_n, cg.r0[kp]));
    }
    Ok(SceneGrads { gaussians: out, planes: plane_grads })
}
