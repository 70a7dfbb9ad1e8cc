//! Evaluation of a model on a dataset's test views (PSNR, SSIM, render speed) and, for a
//! synthetic scene, against its ground truth (`gt/planes.json`, `gt/transmission/`). Shared by
//! `train` (during and after training) and `eval` (a finished run).
use crate::data::{TrainingData, View, resize_area};
use anyhow::{Context, Result};
use std::path::Path;
use std::time::Instant;
use trgs_core::io::{read_planes_json, read_rgb_image};
use trgs_core::metrics::{psnr, ssim};
use trgs_core::scene::ReflectionPlane;
use trgs_render::{GpuContext, GpuScene, Layer, RenderOptions, Renderer};

/// A model as evaluation sees it: scene, renderer and options.
#[derive(Debug)]
pub struct Renderable<'a> {
    pub ctx: &'a GpuContext,
    pub renderer: &'a Renderer,
    pub scene: &'a GpuScene,
    pub options: RenderOptions,
}

impl Renderable<'_> {
    pub fn layer(&self, view: &View, layer: Layer) -> Result<trgs_core::Image<f32>> {
        let frame = self
            .renderer
            .render(self.scene, &view.camera, &self.options)
            .with_context(|| format!("rendering view {}", view.camera.name))?;
        Ok(frame.read_layer(self.ctx, layer))
    }
}

/// PSNR and SSIM of every evaluation view, and their means.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Evaluation {
    /// Training step (0 for a finished model evaluated on its own).
    pub step: u32,
    /// Seconds spent training steps so far (not evaluating or writing checkpoints).
    pub seconds: f64,
    /// (view name, PSNR, SSIM).
    pub views: Vec<(String, f64, f64)>,
    pub psnr: f64,
    pub ssim: f64,
}

/// Evaluate `model` on `data`'s evaluation views.
pub fn evaluate(
    model: &Renderable,
    data: &TrainingData,
    step: u32,
    seconds: f64,
) -> Result<Evaluation> {
    let mut rows = Vec::new();
    for v in data.eval_views() {
        let color = model.layer(v, Layer::Color)?;
        rows.push((v.camera.name.clone(), psnr(&color, &v.image)?, ssim(&color, &v.image)?));
    }
    let n = rows.len().max(1) as f64;
    Ok(Evaluation {
        step,
        seconds,
        psnr: rows.iter().map(|r| r.1).sum::<f64>() / n,
        ssim: rows.iter().map(|r| r.2).sum::<f64>() / n,
        views: rows,
    })
}

/// Frames per second of full renders (every layer, as the renderer produces them) of the
/// evaluation views, after one warm-up render.
pub fn render_fps(model: &Renderable, data: &TrainingData) -> Result<f64> {
    let views = data.eval_views();
    let Some(first) = views.first() else { return Ok(0.0) };
    model.layer(first, Layer::Color)?;
    let t = Instant::now();
    for v in views {
        model.layer(v, Layer::Color)?;
    }
    Ok(views.len() as f64 / t.elapsed().as_secs_f64())
}

/// What a synthetic scene's ground truth says of a model.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct TruthComparison {
    /// Per true plane: the angle in degrees between its normal and the nearest trained plane's,
    /// and the centre distance as a fraction of the true plane's diagonal (NaN with no plane).
    pub planes: Vec<(f64, f64)>,
    /// PSNR of the transmission layer against the true transmission, mean over the test views.
    pub transmission_psnr: Option<f64>,
}

impl std::fmt::Display for TruthComparison {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for (i, (angle, centre)) in self.planes.iter().enumerate() {
            if angle.is_nan() {
                write!(f, "plane {i}: not modelled (the model has no plane); ")?;
                continue;
            }
            write!(
                f,
                "plane {i}: normal off by {angle:.2} deg, centre by {:.2}% of the size; ",
                100.0 * centre
            )?;
        }
        match self.transmission_psnr {
            Some(p) => write!(f, "transmission PSNR {p:.2} dB"),
            None => write!(f, "no true transmission images"),
        }
    }
}

/// Compare with `<root>/gt` when the dataset has one (None otherwise).
pub fn compare_with_truth(
    model: &Renderable,
    planes: &[ReflectionPlane],
    data: &TrainingData,
    root: &Path,
) -> Result<Option<TruthComparison>> {
    let gt = root.join("gt");
    if !gt.is_dir() {
        return Ok(None);
    }
    let mut errors = Vec::new();
    let planes_path = gt.join("planes.json");
    if planes_path.is_file() {
        for spec in read_planes_json(&planes_path)? {
            let Some(truth) = spec.plane else { continue };
            let diag = truth.width.hypot(truth.height);
            let best = planes
                .iter()
                .map(|p| {
                    let cos = p.unit_normal().dot(truth.unit_normal()).abs().min(1.0);
                    (cos.acos().to_degrees(), p.centre.distance(truth.centre) / diag)
                })
                .min_by(|a, b| a.1.total_cmp(&b.1));
            errors.push(best.unwrap_or((f64::NAN, f64::NAN)));
        }
    }
    let mut psnrs = Vec::new();
    for v in &data.test {
        let path = gt.join("transmission").join(&v.camera.name);
        if !path.is_file() {
            continue;
        }
        let truth = read_rgb_image(&path)?;
        let truth = resize_area(&truth, v.camera.width(), v.camera.height());
        let t = model.layer(v, Layer::Transmission)?;
        psnrs.push(psnr(&t, &truth)?);
    }
    let transmission_psnr =
        (!psnrs.is_empty()).then(|| psnrs.iter().sum::<f64>() / psnrs.len() as f64);
    Ok(Some(TruthComparison { planes: errors, transmission_psnr }))
}

/// Write each evaluation view's render `<dir>/<stem>.png` and, with planes, its decomposition
/// (the paper's figure: C_t, C_r, R, R C_r) as `<dir>/layers/<stem>_<layer>.png`.
pub fn write_renders(model: &Renderable, data: &TrainingData, dir: &Path) -> Result<()> {
    use trgs_core::io::{write_png_gray, write_png_rgb};
    let has_planes = !model.scene.planes().is_empty();
    for v in data.eval_views() {
        let stem = Path::new(&v.camera.name)
            .file_stem()
            .map_or_else(|| v.camera.name.clone(), |s| s.to_string_lossy().into_owned());
        let frame = model
            .renderer
            .render(model.scene, &v.camera, &model.options)
            .with_context(|| format!("rendering view {}", v.camera.name))?;
        write_png_rgb(
            &dir.join(format!("{stem}.png")),
            &frame.read_layer(model.ctx, Layer::Color),
        )?;
        if !has_planes {
            continue;
        }
        let layers = dir.join("layers");
        let ct = frame.read_layer(model.ctx, Layer::Transmission);
        let cr = frame.read_layer(model.ctx, Layer::Reflection);
        let r = frame.read_layer(model.ctx, Layer::Strength);
        let mut weighted = cr.clone();
        for (i, px) in weighted.data.chunks_exact_mut(3).enumerate() {
            px.iter_mut().for_each(|c| *c *= r.data[i]);
        }
        write_png_rgb(&layers.join(format!("{stem}_transmission.png")), &ct)?;
        write_png_rgb(&layers.join(format!("{stem}_reflection.png")), &cr)?;
        let r8 =
            trgs_core::Image { width: r.width, height: r.height, channels: 1, data: r.to_u8() };
        write_png_gray(&layers.join(format!("{stem}_strength.png")), &r8)?;
        write_png_rgb(&layers.join(format!("{stem}_weighted_reflection.png")), &weighted)?;
    }
    Ok(())
}
