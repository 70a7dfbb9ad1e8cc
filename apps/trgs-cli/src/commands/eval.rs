//! `eval`: the metrics of a trained model on a dataset's test views, or its training views
//! (PSNR and SSIM per view and mean, render FPS, and for a synthetic scene the plane and
//! transmission errors against its ground truth), printed and written as JSON; optionally the
//! renders and decomposition layers of those views.
use crate::args::SplitArg;
use anyhow::{Context, Result, bail};
use clap::Parser;
use std::path::PathBuf;
use trgs_core::io::{SceneFolder, Split, write_atomic};
use trgs_render::{GpuContext, GpuScene, RenderOptions, Renderer};
use trgs_train::eval::{Renderable, compare_with_truth, evaluate, render_fps, write_renders};
use trgs_train::model::load_model;
use trgs_train::run::parse_positive;
use trgs_train::{LoadOptions, Resolution, TrainingData};

/// Metrics of a trained model on a dataset's test (or training) views: PSNR and SSIM per view
/// and their mean, render FPS, and for a synthetic scene the plane and transmission errors
/// against its ground truth; printed and written as JSON.
#[derive(Debug, Parser)]
#[command(name = "eval", version)]
pub struct Args {
    /// A run folder of `train` (model.ply, planes.json), a .ply (trgs or any INRIA-layout 3DGS
    /// PLY), a .glb (KHR_gaussian_splatting), or an INRIA output folder
    #[arg(long, value_name = "PATH")]
    model: PathBuf,
    /// Trained planes.json [default: beside the PLY or in the run folder]
    #[arg(long, value_name = "FILE")]
    planes: Option<PathBuf>,
    /// The scene folder [default: the run folder's dataset/, where `train` writes the built-in
    /// scene]
    #[arg(long, value_name = "DIR")]
    data: Option<PathBuf>,
    /// Evaluate at width W [default: the images' size, up to 1600 px on the longer side]
    #[arg(long, value_name = "W", conflicts_with = "downscale",
          value_parser = clap::value_parser!(u32).range(1..))]
    resolution: Option<u32>,
    /// Evaluate at 1/F of the image size
    #[arg(long, value_name = "F", value_parser = parse_positive)]
    downscale: Option<f64>,
    /// Evaluate at the photos' own size (by default, as in training, a photo whose longer side
    /// exceeds 1600 px is evaluated at 1600)
    #[arg(long, conflicts_with_all = ["resolution", "downscale"])]
    full_size: bool,
    /// The views to measure: how well the model fits the views it was trained on, or new ones
    #[arg(long, value_enum, default_value = "test")]
    split: SplitArg,
    /// Write the metrics here [default, when --model is a folder: <run folder>/eval.json, with
    /// _<split>, _no-planes and _reference before .json for another split, --no-planes and
    /// --reference (eval_train_no-planes.json); otherwise only printed]
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Render MODEL as a plain 3DGS renderer does: its Gaussians alone, no planes (what other
    /// viewers show of a trgs model)
    #[arg(long)]
    no_planes: bool,
    /// Score against this model's renders (a run folder, .ply or .glb, with its planes) instead
    /// of the photos: how close MODEL comes to it, e.g. a baked export to the model it came from
    #[arg(long, value_name = "PATH")]
    reference: Option<PathBuf>,
    /// Also write each view's render, and with planes its layers (C_t, C_r, R, R C_r), as PNG
    /// under DIR
    #[arg(long, value_name = "DIR")]
    renders: Option<PathBuf>,
}

/// The seam views `trgs merge` recorded in a merged run's metrics.json (None for other runs).
fn seam_views(run: &std::path::Path) -> Option<Vec<String>> {
    trgs_core::io::RunMetrics::read_if_any(&run.join("metrics.json"))?.seam_views
}

pub fn run(matches: &clap::ArgMatches) -> Result<()> {
    let args = super::parsed::<Args>(matches);
    let split = Split::from(args.split);
    let run_dir = args.model.is_dir().then(|| args.model.clone());
    let data_dir = match (&args.data, &run_dir) {
        (Some(d), _) => d.clone(),
        (None, Some(run)) if run.join("dataset").is_dir() => run.join("dataset"),
        _ => bail!("--data is required: {} has no dataset/ folder", args.model.display()),
    };
    let mut model = load_model(&args.model, args.planes.as_deref())?;
    if args.no_planes {
        model.planes.clear();
    }
    let resolution = Resolution::from_flags(args.resolution, args.downscale, args.full_size);
    // Only the views measured are decoded: a few of a capture's hundreds of photos.
    let folder = SceneFolder::open(&data_dir)
        .with_context(|| format!("opening the scene folder {}", data_dir.display()))?;
    let options = LoadOptions { resolution, evaluate: Some(split), progress: None };
    let mut data = TrainingData::load(&folder, &options)?;
    let ctx = GpuContext::new()?;
    if let Some(reference) = &args.reference {
        replace_photos_with_renders(&ctx, reference, &mut data)?;
    }
    let scene = GpuScene::upload(&ctx, &model.gaussians, &model.planes)
        .with_context(|| format!("uploading {}", model.ply.display()))?;
    let renderer = Renderer::new(&ctx);
    let options = RenderOptions { reflection: model.reflection, ..RenderOptions::default() };
    let subject = Renderable { ctx: &ctx, renderer: &renderer, scene: &scene, options };
    let e = evaluate(&subject, &data, 0, 0.0)?;
    for (name, p, s) in &e.views {
        println!("{name}: PSNR {p:.2} dB, SSIM {s:.4}");
    }
    if args.reference.is_some() {
        // A view the two models render alike scores infinite PSNR: pool the error instead.
        let per_view: Vec<f64> = e.views.iter().map(|(_, p, _)| *p).collect();
        println!(
            "against {}: PSNR {:.2} dB pooled over the views' pixels",
            args.reference.as_ref().map_or(String::new(), |r| r.display().to_string()),
            trgs_core::metrics::pooled_psnr(&per_view)
        );
    }
    let fps = render_fps(&subject, &data)?;
    let (w, h) = data.size();
    // A scene without test views is scored on training views: say so.
    let measured = if split == Split::Test { data.eval_views_name() } else { split.name() };
    println!(
        "mean over {} {} views: PSNR {:.2} dB, SSIM {:.4}; {} Gaussians, {}, {fps:.1} FPS at {w}x{h}",
        e.views.len(),
        measured,
        e.psnr,
        e.ssim,
        model.gaussians.len(),
        crate::wording::count(model.planes.len(), "plane")
    );
    if let Some(h) = &e.right_half {
        println!(
            "right halves (the exposure protocol): PSNR {:.2} dB as rendered, {:.2} dB through \
             the exposure fitted on each left half",
            h.psnr, h.psnr_exposure_fitted
        );
    }
    let truth = compare_with_truth(&subject, &model.planes, &data, &data_dir)?;
    if let Some(t) = &truth {
        println!("against the ground truth: {t}");
    }
    let seams = run_dir.as_deref().and_then(seam_views).filter(|_| split == Split::Test);
    let seam_scores = seams.as_ref().map(|seams| {
        let (on, off): (Vec<_>, Vec<_>) = e.views.iter().partition(|(n, _, _)| seams.contains(n));
        let mean = |v: &[&(String, f64, f64)]| {
            (!v.is_empty()).then(|| v.iter().map(|x| x.1).sum::<f64>() / v.len() as f64)
        };
        let (on_psnr, off_psnr) = (mean(&on), mean(&off));
        println!(
            "seam views (where the merged blocks meet): {} of {}, PSNR {}; the others {}",
            on.len(),
            e.views.len(),
            on_psnr.map_or("-".into(), |p| format!("{p:.2} dB")),
            off_psnr.map_or("-".into(), |p| format!("{p:.2} dB"))
        );
        serde_json::json!({"views": on.iter().map(|x| &x.0).collect::<Vec<_>>(),
            "psnr": on_psnr, "other_psnr": off_psnr})
    });
    let json = serde_json::json!({
        "model": model.ply,
        "data": data_dir,
        "split": measured,
        "no_planes": args.no_planes,
        "reference": args.reference,
        "psnr": e.psnr,
        "ssim": e.ssim,
        "views": e.views.iter().map(|(n, p, s)| serde_json::json!({"name": n, "psnr": p, "ssim": s})).collect::<Vec<_>>(),
        "right_half": e.right_half,
        "gaussians": model.gaussians.len(),
        "planes": model.planes.len(),
        "render_fps": fps,
        "resolution": [w, h],
        "truth": truth,
        "seams": seam_scores,
    });
    if let Some(dir) = &args.renders {
        write_renders(&subject, &data, dir)?;
        println!("renders written to {}", dir.display());
    }
    let default_name = eval_file_name(split, args.no_planes, args.reference.is_some());
    let out = args.out.or_else(|| run_dir.map(|r| r.join(default_name)));
    if let Some(out) = out {
        write_atomic(&out, serde_json::to_string_pretty(&json)?.as_bytes())?;
        println!("metrics written to {}", out.display());
    }
    Ok(())
}

/// The file a run folder's evaluation is written to: what was measured is in the name, so that
/// a score against a reference or without the planes never replaces the run's own eval.json.
fn eval_file_name(split: Split, no_planes: bool, reference: bool) -> String {
    let mut name = String::from("eval");
    if split != Split::Test {
        name += &format!("_{}", split.name());
    }
    if no_planes {
        name += "_no-planes";
    }
    if reference {
        name += "_reference";
    }
    name + ".json"
}

/// The eval views' photos replaced by renders of the model at `reference` (with its planes), so
/// that the scores say how close the evaluated model comes to it.
fn replace_photos_with_renders(
    ctx: &GpuContext,
    reference: &std::path::Path,
    data: &mut TrainingData,
) -> Result<()> {
    let model = load_model(reference, None)?;
    let scene = GpuScene::upload(ctx, &model.gaussians, &model.planes)
        .with_context(|| format!("uploading {}", model.ply.display()))?;
    let renderer = Renderer::new(ctx);
    let options = RenderOptions { reflection: model.reflection, ..RenderOptions::default() };
    let views = if data.test.is_empty() { &mut data.train } else { &mut data.test };
    for v in views.iter_mut() {
        let frame = renderer.render(&scene, &v.camera, &options).with_context(|| {
            format!("rendering view {:?} of {}", v.camera.name, reference.display())
        })?;
        v.image = frame.read_layer(ctx, trgs_render::Layer::Color)?.quantised();
    }
    Ok(())
}
