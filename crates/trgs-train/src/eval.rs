//! Evaluation of a model on a dataset's test views (PSNR, SSIM, render speed) and, for a
//! synthetic scene, against its ground truth (`gt/planes.json`, `gt/transmission/`). Shared by
//! `train` (during and after training) and `eval` (a finished run).
use crate::data::{TrainingData, View, resize_area_u8};
use anyhow::{Context, Result};
use std::path::Path;
use std::time::Instant;
use trgs_core::Image;
use trgs_core::fit::fit_exposure;
use trgs_core::io::{read_planes_json, read_rgb8_image};
use trgs_core::metrics::{psnr_covered, ssim_covered};
use trgs_core::scene::ReflectionPlane;
use trgs_render::{Frame, GpuContext, GpuScene, Layer, RenderError, RenderOptions, Renderer};

/// A model as evaluation sees it: scene, renderer and options.
#[derive(Debug)]
pub struct Renderable<'a> {
    pub ctx: &'a GpuContext,
    pub renderer: &'a Renderer,
    pub scene: &'a GpuScene,
    pub options: RenderOptions,
}

impl Renderable<'_> {
    /// One render of `view`, every layer in it (read several layers from one frame rather than
    /// rendering once per layer).
    pub fn frame(&self, view: &View) -> Result<Frame> {
        self.renderer
            .render(self.scene, &view.camera, &self.options)
            .with_context(|| format!("rendering view {}", view.camera.name))
    }

    pub fn layer(&self, view: &View, layer: Layer) -> Result<trgs_core::Image<f32>> {
        Ok(self.frame(view)?.read_layer(self.ctx, layer)?)
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
    /// The exposure protocol's scores (absent from runs that predate it).
    #[serde(default)]
    pub right_half: Option<RightHalfScores>,
}

/// Test PSNR on the right half of each test photo, with the render as it is and with the
/// render through an exposure fitted on the photo's left half ([`fit_exposure`]): the INRIA
/// code's `train_test_exp` protocol, which scores a model trained with per-view exposures (whose
/// test views' exposures it cannot know) fairly against one trained without. Means over the
/// test views.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RightHalfScores {
    pub psnr: f64,
    pub psnr_exposure_fitted: f64,
}

/// The right-half PSNR of `render` against `photo` (same size, RGB, uncovered pixels zero in
/// both), as it is and through the exposure fitted on the left half's `covered` pixels.
pub fn right_half_psnr(
    render: &Image<f32>,
    photo: &Image<f32>,
    covered: Option<&Image<u8>>,
) -> Result<(f64, f64)> {
    let half = render.width / 2;
    let is_covered = |x: u32, y: u32| covered.is_none_or(|c| c.get(x, y, 0) != 0);
    let fitted = fit_exposure(render, photo, |x, y| x < half && is_covered(x, y));
    let exposed = render.map(f64::from);
    let exposed = trgs_core::reference::exposure(&exposed, &fitted);
    let exposed = exposed.map(|v| v.clamp(0.0, 1.0) as f32);
    let exposed = match covered {
        Some(c) => exposed.zero_uncovered(c),
        None => exposed,
    };
    let right = |im: &Image<f32>| im.columns(half, im.width);
    let right_covered = covered.map(|c| c.columns(half, c.width));
    let photo = right(photo);
    let score = |im: &Image<f32>| psnr_covered(&right(im), &photo, right_covered.as_ref());
    Ok((score(render)?, score(&exposed)?))
}

/// A rendered layer as it is scored: clamped to [0, 1], and zero where the photo covers
/// nothing (an undistorted view's border).
fn shown(layer: Image<f32>, covered: Option<&Image<u8>>) -> Image<f32> {
    let layer = layer.map(|v| v.clamp(0.0, 1.0));
    match covered {
        Some(c) => layer.zero_uncovered(c),
        None => layer,
    }
}

/// Evaluate `model` on `data`'s evaluation views.
pub fn evaluate(
    model: &Renderable,
    data: &TrainingData,
    step: u32,
    seconds: f64,
) -> Result<Evaluation> {
    let mut rows = Vec::new();
    let mut halves = Vec::new();
    for v in data.eval_views() {
        // Scored as a viewer shows it (and as INRIA's and gsplat's metrics score it): clamped to
        // [0, 1]; the renderer leaves colour unclamped above. Only what the photo shows counts,
        // as in the loss.
        let color = shown(model.layer(v, Layer::Color)?, v.covered.as_ref());
        let image = v.image.to_f32();
        // Scored over the pixels the photo covers: the zeroed rest would count as matches.
        let covered = v.covered.as_ref();
        let scores =
            (psnr_covered(&color, &image, covered)?, ssim_covered(&color, &image, covered)?);
        rows.push((v.camera.name.clone(), scores.0, scores.1));
        halves.push(right_half_psnr(&color, &image, v.covered.as_ref())?);
    }
    let n = rows.len().max(1) as f64;
    let mean = |f: &dyn Fn(&(f64, f64)) -> f64| halves.iter().map(f).sum::<f64>() / n;
    Ok(Evaluation {
        step,
        seconds,
        psnr: rows.iter().map(|r| r.1).sum::<f64>() / n,
        ssim: rows.iter().map(|r| r.2).sum::<f64>() / n,
        views: rows,
        right_half: (!halves.is_empty()).then(|| RightHalfScores {
            psnr: mean(&|h| h.0),
            psnr_exposure_fitted: mean(&|h| h.1),
        }),
    })
}

/// Frames per second of full renders (every layer, as the renderer produces them) of the
/// evaluation views, each waited for: the render's own time, as a viewer pays it, without reading
/// the image back. The renders go into one frame whose key list is sized from earlier frames
/// (a viewer's steady state, [`Renderer::render_finished`]) rather than read back halfway
/// through each; a render whose list turns out too small is rendered again, and both count.
/// After one warm-up render (pipelines, buffers).
pub fn render_fps(model: &Renderable, data: &TrainingData) -> Result<f64> {
    let views = data.eval_views();
    let Some(first) = views.first() else { return Ok(0.0) };
    let mut frame = Frame::default();
    let mut render = |view: &View| -> Result<()> {
        let wait = |_: &Frame| -> Result<(), RenderError> {
            Ok(trgs_render::toolkit::gpu::wait_for_gpu(model.ctx, "a timed render")?)
        };
        (model.renderer)
            .render_finished(model.scene, &view.camera, &model.options, &mut frame, wait)
            .with_context(|| format!("rendering view {}", view.camera.name))
    };
    render(first)?;
    let t = Instant::now();
    for v in views {
        render(v)?;
    }
    Ok(views.len() as f64 / t.elapsed().as_secs_f64())
}

/// What a synthetic scene's ground truth says of a model.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct TruthComparison {
    /// Per true plane: the angle in degrees between its normal and the nearest trained plane's,
    /// and the centre distance as a fraction of the true plane's diagonal (NaN with no plane).
    #[serde(deserialize_with = "nan_for_null")]
    pub planes: Vec<(f64, f64)>,
    /// Per true plane: the base reflectance R0 of the nearest trained plane (NaN with no plane)
    /// and the truth's.
    #[serde(default, deserialize_with = "nan_for_null")]
    pub r0: Vec<(f64, f64)>,
    /// PSNR of the transmission layer against the true transmission, mean over the evaluation
    /// views (the test views unless `eval --split` says otherwise).
    pub transmission_psnr: Option<f64>,
    /// PSNR of the final image against the test images where the glass shows a reflection
    /// (the image differs from the true transmission) and everywhere else, each over the pooled
    /// pixels of all test views: where TR-Gaussians and plain 3DGS differ, and where they should
    /// not. None without true transmission images or without such pixels.
    #[serde(default)]
    pub reflection_region_psnr: Option<f64>,
    #[serde(default)]
    pub elsewhere_psnr: Option<f64>,
    /// PSNR of the transmission layer against the true transmission in that reflection region:
    /// how clean the separation is where it matters (outside it, C_t is the image). For a model
    /// without planes, its final image.
    #[serde(default)]
    pub transmission_region_psnr: Option<f64>,
    /// Share of the test pixels in the reflection region.
    #[serde(default)]
    pub reflection_region_share: Option<f64>,
}

/// Pairs written by serde_json, which writes NaN (no plane to compare with) as null.
fn nan_for_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Vec<(f64, f64)>, D::Error> {
    let pairs: Vec<(Option<f64>, Option<f64>)> = serde::Deserialize::deserialize(d)?;
    Ok(pairs.into_iter().map(|(a, b)| (a.unwrap_or(f64::NAN), b.unwrap_or(f64::NAN))).collect())
}

impl std::fmt::Display for TruthComparison {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // Planes are numbered from 1 here as in the run's lines (their mask labels).
        for (i, (angle, centre)) in self.planes.iter().enumerate() {
            if angle.is_nan() {
                write!(f, "plane {}: not modelled (the model has no plane); ", i + 1)?;
                continue;
            }
            write!(
                f,
                "plane {}: normal off by {angle:.2} deg, centre by {:.2}% of the size",
                i + 1,
                100.0 * centre
            )?;
            match self.r0.get(i) {
                Some((trained, truth)) => write!(f, ", R0 {trained:.3} (truth {truth:.3}); ")?,
                None => write!(f, "; ")?,
            }
        }
        match self.transmission_psnr {
            Some(p) => write!(f, "transmission PSNR {p:.2} dB"),
            None => write!(f, "no true transmission images"),
        }?;
        if let (Some(r), Some(e), Some(share)) =
            (self.reflection_region_psnr, self.elsewhere_psnr, self.reflection_region_share)
        {
            write!(
                f,
                "; final image {r:.2} dB where the glass reflects ({:.0}% of the pixels), \
                 {e:.2} dB elsewhere",
                100.0 * share
            )?;
        }
        if let Some(t) = self.transmission_region_psnr {
            write!(f, "; transmission {t:.2} dB from the truth where the glass reflects")?;
        }
        Ok(())
    }
}

/// A pixel belongs to the reflection region when the image and the true transmission differ by
/// more than this in some channel (a level of an 8-bit image is 1/255; resampling blends levels).
pub const REFLECTION_REGION_THRESHOLD: f32 = 0.5 / 255.0;

/// Squared error of `render` against `target`, summed per region: [reflection region,
/// elsewhere], each as (sum over the samples, number of samples). The reflection region is where
/// the dataset's `image` differs from the true transmission `truth`; `target` is the image for the
/// final render and the truth for the transmission layer. Pixels `covered` marks zero (an
/// undistorted view's border, where the photo shows nothing) are in neither.
pub fn region_errors(
    render: &trgs_core::Image<f32>,
    target: &trgs_core::Image<f32>,
    image: &trgs_core::Image<f32>,
    truth: &trgs_core::Image<f32>,
    covered: Option<&Image<u8>>,
) -> Result<[(f64, usize); 2]> {
    let same = |a: &trgs_core::Image<f32>| {
        (a.width, a.height, a.channels) == (image.width, image.height, image.channels)
    };
    anyhow::ensure!(
        same(render) && same(target) && same(truth),
        "region errors need images of one size: render {}x{}x{}, target {}x{}x{}, \
         image {}x{}x{}, truth {}x{}x{}",
        render.width,
        render.height,
        render.channels,
        target.width,
        target.height,
        target.channels,
        image.width,
        image.height,
        image.channels,
        truth.width,
        truth.height,
        truth.channels
    );
    let c = image.channels.max(1) as usize;
    let mut out = [(0.0, 0usize); 2];
    anyhow::ensure!(
        covered.is_none_or(|m| (m.width, m.height) == (image.width, image.height)),
        "region errors need a coverage mask of the images' size"
    );
    let pixels = render.data.chunks(c).zip(target.data.chunks(c));
    let photo = image.data.chunks(c).zip(truth.data.chunks(c));
    for (k, ((r, g), (i, t))) in pixels.zip(photo).enumerate() {
        if covered.is_some_and(|m| m.data[k * m.channels as usize] == 0) {
            continue;
        }
        let reflects = i.iter().zip(t).any(|(a, b)| (a - b).abs() > REFLECTION_REGION_THRESHOLD);
        let e: f64 = r.iter().zip(g).map(|(&a, &b)| (f64::from(a) - f64::from(b)).powi(2)).sum();
        let slot = &mut out[usize::from(!reflects)];
        slot.0 += e;
        slot.1 += c;
    }
    Ok(out)
}

fn psnr_of(sum: f64, samples: usize) -> Option<f64> {
    (samples > 0).then(|| 10.0 * (samples as f64 / sum.max(f64::MIN_POSITIVE)).log10())
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
    let mut r0 = Vec::new();
    let planes_path = gt.join("planes.json");
    if planes_path.is_file() {
        for spec in read_planes_json(&planes_path)? {
            let Some(truth) = spec.plane else { continue };
            let best = planes
                .iter()
                .map(|p| {
                    let (angle, centre) = p.error_against(&truth);
                    (angle, centre, p.r0())
                })
                .min_by(|a, b| a.1.total_cmp(&b.1));
            let (angle, centre, trained) = best.unwrap_or((f64::NAN, f64::NAN, f64::NAN));
            errors.push((angle, centre));
            r0.push((trained, truth.r0()));
        }
    }
    let mut psnrs = Vec::new();
    // [final image, transmission layer] x [reflection region, elsewhere]
    let mut regions = [[(0.0, 0usize); 2]; 2];
    for v in data.eval_views() {
        let path = gt.join("transmission").join(&v.camera.name);
        if !path.is_file() {
            continue;
        }
        // Decoded at 8 bits, as the photos are: a 12 MP truth is 36 MB so, 144 MB as f32.
        let truth = read_rgb8_image(&path)?;
        // The truth is a photo like the view's own: through its lens, when it has one.
        let truth = match &v.undistortion {
            None => resize_area_u8(&truth, v.camera.width(), v.camera.height()),
            Some(u) => {
                let (pw, ph) = u.photo_size();
                u.warp_image(&resize_area_u8(&truth, pw, ph))
                    .with_context(|| path.display().to_string())?
                    .0
            }
        };
        let frame = model.frame(v)?;
        let image = v.image.to_f32();
        // Over the pixels the photo covers, as `evaluate` scores.
        let covered = v.covered.as_ref();
        let t = shown(frame.read_layer(model.ctx, Layer::Transmission)?, covered);
        psnrs.push(psnr_covered(&t, &truth, covered)?);
        let color = shown(frame.read_layer(model.ctx, Layer::Color)?, covered);
        let context = || format!("comparing {} with {}", v.camera.name, path.display());
        let splits = [
            region_errors(&color, &image, &image, &truth, covered).with_context(context)?,
            region_errors(&t, &truth, &image, &truth, covered).with_context(context)?,
        ];
        for (totals, split) in regions.iter_mut().zip(splits) {
            for (total, part) in totals.iter_mut().zip(split) {
                total.0 += part.0;
                total.1 += part.1;
            }
        }
    }
    let [regions, transmission_regions] = regions;
    let transmission_psnr =
        (!psnrs.is_empty()).then(|| psnrs.iter().sum::<f64>() / psnrs.len() as f64);
    let samples = regions[0].1 + regions[1].1;
    Ok(Some(TruthComparison {
        planes: errors,
        r0,
        transmission_psnr,
        reflection_region_psnr: psnr_of(regions[0].0, regions[0].1),
        elsewhere_psnr: psnr_of(regions[1].0, regions[1].1),
        transmission_region_psnr: psnr_of(transmission_regions[0].0, transmission_regions[0].1),
        reflection_region_share: (samples > 0).then(|| regions[0].1 as f64 / samples as f64),
    }))
}

/// Write each evaluation view's render `<dir>/<stem>.png` and, with planes, its decomposition
/// (the paper's figure: C_t, C_r, R, R C_r) as `<dir>/layers/<stem>_<layer>.png`, where the stem
/// is the view's name without extension, folders kept (`view_output_stem`).
pub fn write_renders(model: &Renderable, data: &TrainingData, dir: &Path) -> Result<()> {
    use trgs_core::io::{write_png_gray, write_png_rgb};
    let has_planes = !model.scene.planes().is_empty();
    for (i, v) in data.eval_views().iter().enumerate() {
        let stem = trgs_core::io::view_output_stem(&v.camera.name)
            .unwrap_or_else(|| format!("view_{i:04}"));
        let frame = model.frame(v)?;
        write_png_rgb(
            &dir.join(format!("{stem}.png")),
            &frame.read_layer(model.ctx, Layer::Color)?,
        )?;
        if !has_planes {
            continue;
        }
        let layers = dir.join("layers");
        let ct = frame.read_layer(model.ctx, Layer::Transmission)?;
        let cr = frame.read_layer(model.ctx, Layer::Reflection)?;
        let r = frame.read_layer(model.ctx, Layer::Strength)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use trgs_core::Image;

    fn rgb(pixels: &[[f32; 3]]) -> Image<f32> {
        Image { width: pixels.len() as u32, height: 1, channels: 3, data: pixels.concat() }
    }

    #[test]
    fn the_right_half_is_scored_through_the_exposure_of_the_left() {
        // A photo taken darker and warmer than the render: the fit on the left half explains
        // the right half, which the render as it is does not.
        let mut render = Image::<f32>::new(32, 16, 3);
        for (i, v) in render.data.iter_mut().enumerate() {
            *v = ((i * 37) % 101) as f32 / 101.0;
        }
        let mut photo = render.map(|v| v * 0.7);
        for px in photo.data.chunks_mut(3) {
            px[0] += 0.05;
        }
        let (plain, fitted) = right_half_psnr(&render, &photo, None).expect("same size");
        assert!(plain < 25.0, "{plain}");
        assert!(fitted > 50.0, "{fitted}");
        let (same, same_fitted) = right_half_psnr(&render, &render, None).expect("same size");
        assert!(same.is_infinite() || same > 100.0, "{same}");
        assert!(same_fitted > 60.0, "{same_fitted}");
    }

    #[test]
    fn regions_split_where_the_image_leaves_the_transmission() {
        // Pixel 0: the glass adds a reflection; pixel 1: resampling noise of 0.4 of an 8-bit level,
        // below the threshold; pixel 2: no glass.
        let truth = rgb(&[[0.2, 0.2, 0.2], [0.5, 0.5, 0.5], [0.9, 0.1, 0.3]]);
        let image = rgb(&[[0.3, 0.25, 0.2], [0.5, 0.5, 0.5 + 0.4 / 255.0], [0.9, 0.1, 0.3]]);
        let render = rgb(&[[0.3, 0.15, 0.2], [0.6, 0.5, 0.5], [0.9, 0.1, 0.0]]);
        let [inside, outside] =
            region_errors(&render, &image, &image, &truth, None).expect("same sizes");
        assert_eq!(inside.1, 3);
        assert!((inside.0 - 0.01).abs() < 1e-7, "{inside:?}");
        assert_eq!(outside.1, 6);
        let want = 0.01 + (0.4f64 / 255.0).powi(2) + 0.09;
        assert!((outside.0 - want).abs() < 1e-6, "{outside:?} against {want}");
        assert!(
            (psnr_of(inside.0, inside.1).expect("pixels") - 10.0 * (3.0f64 / 0.01).log10()).abs()
                < 1e-6
        );
        assert_eq!(psnr_of(0.0, 0), None);
    }

    #[test]
    fn layers_are_scored_clamped_and_only_where_the_photo_covers() {
        let covered = Image { width: 3, height: 1, channels: 1, data: vec![1, 1, 0] };
        let layer = rgb(&[[1.4, 0.5, -0.1], [0.2, 0.2, 0.2], [0.7, 0.7, 0.7]]);
        let scored = shown(layer, Some(&covered));
        assert_eq!(scored.data, [1.0, 0.5, 0.0, 0.2, 0.2, 0.2, 0.0, 0.0, 0.0]);
        // The uncovered pixel is in neither region, whatever the render holds there.
        let truth = rgb(&[[0.2, 0.2, 0.2], [0.5, 0.5, 0.5], [0.0, 0.0, 0.0]]);
        let image = rgb(&[[0.3, 0.25, 0.2], [0.5, 0.5, 0.5], [0.0, 0.0, 0.0]]);
        let render = rgb(&[[0.3, 0.25, 0.2], [0.5, 0.5, 0.5], [0.9, 0.9, 0.9]]);
        let [inside, outside] =
            region_errors(&render, &image, &image, &truth, Some(&covered)).expect("sizes");
        assert_eq!((inside, outside), ((0.0, 3), (0.0, 3)));
    }

    #[test]
    fn the_transmission_is_scored_against_the_truth_in_the_same_regions() {
        // The region still comes from image against truth; the error is the layer's against the
        // truth: pixel 0 reflects (layer 0.1 off the truth in red), pixel 1 does not (0.2 off).
        let truth = rgb(&[[0.2, 0.2, 0.2], [0.5, 0.5, 0.5]]);
        let image = rgb(&[[0.3, 0.25, 0.2], [0.5, 0.5, 0.5]]);
        let layer = rgb(&[[0.3, 0.2, 0.2], [0.5, 0.7, 0.5]]);
        let [inside, outside] = region_errors(&layer, &truth, &image, &truth, None).expect("sizes");
        assert_eq!((inside.1, outside.1), (3, 3));
        assert!((inside.0 - 0.01).abs() < 1e-7, "{inside:?}");
        assert!((outside.0 - 0.04).abs() < 1e-7, "{outside:?}");
    }

    #[test]
    fn region_errors_refuse_images_of_different_sizes() {
        let a = rgb(&[[0.0; 3], [0.0; 3]]);
        let b = rgb(&[[0.0; 3]]);
        let err = region_errors(&a, &a, &a, &b, None).expect_err("sizes differ").to_string();
        assert!(err.contains("truth 1x1x3"), "{err}");
        let err = region_errors(&a, &b, &a, &a, None).expect_err("sizes differ").to_string();
        assert!(err.contains("target 1x1x3"), "{err}");
    }
}
