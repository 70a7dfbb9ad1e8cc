//! A trained model baked for plain 3DGS viewers (`trgs_core::bake`) on the GPU: the strength of
//! each view comes from trgs's renderer, and the bake's fidelity is measured as plain renders
//! of the baked model against trgs's renders with the planes.
use anyhow::{Context, Result};
use trgs_core::bake::{BakeReport, StrengthView, bake};
use trgs_core::io::model::Model;
use trgs_core::metrics::{pooled_psnr, psnr};
use trgs_core::{Camera, Gaussians, Image};
use trgs_render::{GpuContext, GpuScene, Layer, RenderOptions, Renderer};

/// The longest side the strength is rendered at: it is smooth (Schlick times the mask), and a
/// capture's hundreds of views at full size would not fit in memory side by side.
pub const STRENGTH_LONG_SIDE: u32 = 512;

/// The views the bake's fidelity is measured on, at most: spread over the capture.
pub const MEASURED_VIEWS: usize = 16;

/// `camera` with its longer side at most `long` pixels (the same view, fewer pixels).
pub fn at_most(camera: &Camera, long: u32) -> Camera {
    let (w, h) = (camera.width(), camera.height());
    if w.max(h) <= long {
        return camera.clone();
    }
    let s = f64::from(long) / f64::from(w.max(h));
    let size = |d: u32| ((f64::from(d) * s).round() as u32).max(1);
    Camera::new(camera.name.clone(), camera.intrinsics.resized(size(w), size(h)), camera.pose)
}

/// Up to `count` of `cameras`, spread evenly over them (all when there are no more).
pub fn spread(cameras: &[Camera], count: usize) -> Vec<Camera> {
    if cameras.len() <= count {
        return cameras.to_vec();
    }
    (0..count).map(|i| cameras[i * cameras.len() / count].clone()).collect()
}

/// `model` with its planes on the GPU, once for both the bake and its check.
pub fn upload_model(ctx: &GpuContext, model: &Model) -> Result<GpuScene> {
    GpuScene::upload(ctx, &model.gaussians, &model.planes)
        .with_context(|| format!("{}: invalid model", model.ply.display()))
}

/// The model's Gaussians baked with the strength seen from `cameras` (its training views),
/// rendered at most [`STRENGTH_LONG_SIDE`] pixels long; `scene` is `model` on the GPU
/// ([`upload_model`]).
pub fn bake_for_plain_viewers(
    ctx: &GpuContext,
    model: &Model,
    scene: &GpuScene,
    cameras: &[Camera],
) -> Result<(Gaussians<f32>, BakeReport)> {
    if model.planes.is_empty() {
        return Ok(bake(&model.gaussians, &[], &[]));
    }
    let renderer = Renderer::new(ctx);
    let options = RenderOptions { reflection: model.reflection, ..RenderOptions::default() };
    let cameras: Vec<Camera> = cameras.iter().map(|c| at_most(c, STRENGTH_LONG_SIDE)).collect();
    let strengths: Vec<Image<f32>> = cameras
        .iter()
        .map(|c| {
            let frame = renderer
                .render(scene, c, &options)
                .with_context(|| format!("rendering view {:?}", c.name))?;
            Ok(frame.read_layer(ctx, Layer::Strength)?)
        })
        .collect::<Result<_>>()?;
    let views: Vec<StrengthView> = cameras
        .iter()
        .zip(&strengths)
        .map(|(camera, strength)| StrengthView { camera, strength })
        .collect();
    Ok(bake(&model.gaussians, &model.planes, &views))
}

/// PSNR over `cameras` of plain renders of each of `candidates` (no planes, as other viewers
/// draw them) against trgs's renders of `model` with its planes, rendered once per view: the
/// squared error pooled over every view's pixels (`metrics::pooled_psnr`), since a view that
/// sees no plane renders the same both ways. `with_planes` is `model` on the GPU
/// ([`upload_model`]).
pub fn plain_render_psnr(
    ctx: &GpuContext,
    model: &Model,
    with_planes: &GpuScene,
    candidates: &[&Gaussians<f32>],
    cameras: &[Camera],
) -> Result<Vec<f64>> {
    let renderer = Renderer::new(ctx);
    let plain: Vec<GpuScene> = candidates
        .iter()
        .map(|g| GpuScene::upload(ctx, g, &[]).context("uploading a plain model"))
        .collect::<Result<_>>()?;
    let options = RenderOptions { reflection: model.reflection, ..RenderOptions::default() };
    let mut per_view = vec![Vec::with_capacity(cameras.len()); candidates.len()];
    for c in cameras {
        let render = |scene: &GpuScene| -> Result<Image<f32>> {
            let frame = renderer
                .render(scene, c, &options)
                .with_context(|| format!("rendering view {:?}", c.name))?;
            Ok(frame.read_layer(ctx, Layer::Color)?)
        };
        let reference = render(with_planes)?;
        for (scores, scene) in per_view.iter_mut().zip(&plain) {
            scores.push(psnr(&render(scene)?, &reference)?);
        }
    }
    Ok(per_view.iter().map(|v| pooled_psnr(v)).collect())
}

#[cfg(test)]
mod tests {
    #[test]
    fn strength_views_are_smaller_and_measured_views_spread() {
        use trgs_core::{Intrinsics, Pose};
        let k = Intrinsics::from_fov_x(1.0, 1600, 1200);
        let c = super::Camera::new("big", k, Pose::default());
        let small = super::at_most(&c, 512);
        assert_eq!((small.width(), small.height()), (512, 384));
        assert!((small.intrinsics.fx / k.fx - 0.32).abs() < 1e-12, "the same field of view");
        assert_eq!(super::at_most(&small, 512).width(), 512);
        let many: Vec<super::Camera> =
            (0..100).map(|i| super::Camera::new(format!("v{i}"), k, Pose::default())).collect();
        let picked: Vec<String> = super::spread(&many, 4).into_iter().map(|c| c.name).collect();
        assert_eq!(picked, ["v0", "v25", "v50", "v75"]);
        assert_eq!(super::spread(&many[..3], 16).len(), 3);
    }
}
