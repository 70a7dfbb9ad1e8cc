//! `render`: render a model from the cameras of a dataset folder or a camera path, writing a PNG
//! of the final image per view and an OpenEXR of its linear layers (depth, strength,
//! transmission, reflection, mask), with a progress bar.
use crate::args::{SplitArg, parse_colour};
use crate::exr_layers::write_exr;
use anyhow::{Context, Result, bail};
use clap::Parser;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::time::Instant;
use trgs_core::io::{SceneFolder, Split, read_transforms, write_png_rgb};
use trgs_core::plane_math::{flip_horizontal, mirror_camera, mirrored_pass_gaussians};
use trgs_core::scene::Camera;
use trgs_render::{GpuContext, GpuScene, Layer, RenderOptions, Renderer};
use trgs_train::model::{Model, load_model};

/// Render a model from a dataset's cameras or a camera path: a PNG of the final image per view
/// and an OpenEXR of its linear layers (transmission.RGB, reflection.RGB, strength.Y, mask.Y,
/// depth.Z).
#[derive(Debug, Parser)]
#[command(name = "render", version)]
pub struct Args {
    /// A .ply (trgs or any INRIA-layout 3DGS PLY), a .glb (KHR_gaussian_splatting, planes
    /// included), or a run folder holding model.ply or point_cloud/iteration_*/point_cloud.ply
    #[arg(long, value_name = "PATH")]
    model: PathBuf,
    /// Trained planes.json [default: planes.json beside the PLY or in the run folder; none
    /// means no planes]
    #[arg(long, value_name = "FILE")]
    planes: Option<PathBuf>,
    /// A scene folder (COLMAP or transforms.json) or a transforms.json camera path
    #[arg(long, value_name = "PATH")]
    cameras: PathBuf,
    /// With a scene folder: the views to render
    #[arg(long, value_enum, default_value = "test")]
    split: SplitArg,
    /// Output folder
    #[arg(long, value_name = "DIR", default_value = "renders")]
    out: PathBuf,
    /// Background colour in [0, 1]
    #[arg(long, value_name = "R,G,B", default_value = "0,0,0", value_parser = parse_colour)]
    background: [f32; 3],
    /// Only the PNGs
    #[arg(long)]
    no_exr: bool,
    /// Instead, what plane N (1 = the first in planes.json) reflects: each camera's mirrored view
    /// over the whole image, aligned with the camera's pixels (inside the plane's rectangle it is
    /// the raw reflection C_raw on the default black background), written as
    /// <view>_mirror<N>.png; cameras behind the plane are skipped
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    mirror: Option<u32>,
}

/// The cameras to render and their output names.
fn cameras(path: &Path, split: Split) -> Result<Vec<Camera>> {
    if path.is_file() {
        return Ok(read_transforms(path)?.into_iter().map(|f| f.camera).collect());
    }
    let folder = SceneFolder::open(path)?;
    let views = folder.views.iter().filter(|v| split.holds(folder.is_test(&v.camera.name)));
    Ok(views.map(|v| v.camera.clone()).collect())
}

/// The output stem of a camera (its name without extension, folders kept), or its index.
fn stem(name: &str, index: usize) -> String {
    trgs_core::io::view_output_stem(name).unwrap_or_else(|| format!("view_{index:04}"))
}

fn progress_bar(len: usize) -> ProgressBar {
    let bar = ProgressBar::new(len as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} views  {per_sec}  eta {eta}  {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar
}

/// `--mirror N`: every camera's view of what plane N reflects (`mirror_camera`), from the
/// Gaussians its mirrored pass renders, flipped back into the camera's pixel grid.
fn render_mirror(
    args: &Args,
    model: &Model,
    cams: &[Camera],
    renderer: &Renderer,
    options: &RenderOptions,
    n: usize,
) -> Result<()> {
    let Some(plane) = model.planes.get(n - 1) else {
        bail!(
            "--mirror {n}: {} has {} planes (planes are numbered from 1 in planes.json order)",
            model.ply.display(),
            model.planes.len()
        );
    };
    let ctx = renderer.context();
    let front = mirrored_pass_gaussians(plane, &model.gaussians);
    let scene = GpuScene::upload(ctx, &front, &[])
        .with_context(|| format!("{}: invalid model", model.ply.display()))?;
    let bar = progress_bar(cams.len());
    let (mut written, mut behind) = (0, Vec::new());
    let mut frame = trgs_render::Frame::default();
    for (i, cam) in cams.iter().enumerate() {
        let name = stem(&cam.name, i);
        bar.inc(1);
        // From behind the plane there is no reflection to show.
        if !(plane.signed_distance(cam.pose.centre()) > 0.0) {
            behind.push(name);
            continue;
        }
        let mirrored = mirror_camera(plane, cam);
        renderer
            .render_into(&scene, &mirrored, options, &mut frame)
            .with_context(|| format!("rendering the mirrored view of {:?}", cam.name))?;
        let color = flip_horizontal(&frame.read_layer(ctx, Layer::Color)?);
        write_png_rgb(&args.out.join(format!("{name}_mirror{n}.png")), &color)?;
        written += 1;
        bar.set_message(name);
    }
    bar.finish_and_clear();
    println!(
        "plane {n}: {} front-side primary Gaussians; mirrored views of {written} cameras \
         written to {}",
        front.len(),
        args.out.display()
    );
    if !behind.is_empty() {
        println!("skipped (behind the plane, no reflection): {}", behind.join(", "));
    }
    Ok(())
}

pub fn run(matches: &clap::ArgMatches) -> Result<()> {
    let args = super::parsed::<Args>(matches);
    let model = load_model(&args.model, args.planes.as_deref())?;
    let split = Split::from(args.split);
    let cams = cameras(&args.cameras, split)?;
    if cams.is_empty() {
        bail!("{}: no cameras in the {} split", args.cameras.display(), split.name());
    }
    let ctx = GpuContext::new()?;
    println!(
        "{}: {} Gaussians (SH degree {}), {}; {} on {}",
        model.ply.display(),
        model.gaussians.len(),
        model.gaussians.sh_degree,
        crate::wording::count(model.planes.len(), "plane"),
        crate::wording::count(cams.len(), "view"),
        ctx.adapter()
    );
    let renderer = Renderer::new(&ctx);
    let options = RenderOptions {
        background: args.background,
        reflection: model.reflection,
        ..Default::default()
    };
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating the output folder {}", args.out.display()))?;
    if let Some(n) = args.mirror {
        return render_mirror(&args, &model, &cams, &renderer, &options, n as usize);
    }
    let scene = GpuScene::upload(&ctx, &model.gaussians, &model.planes)
        .with_context(|| format!("{}: invalid model", model.ply.display()))?;
    let bar = progress_bar(cams.len());
    let t = Instant::now();
    let mut frame = trgs_render::Frame::default();
    for (i, cam) in cams.iter().enumerate() {
        renderer
            .render_into(&scene, cam, &options, &mut frame)
            .with_context(|| format!("rendering view {:?}", cam.name))?;
        let name = stem(&cam.name, i);
        let color = frame.read_layer(&ctx, Layer::Color)?;
        write_png_rgb(&args.out.join(format!("{name}.png")), &color)?;
        if !args.no_exr {
            let layers: Vec<(Layer, trgs_core::Image<f32>)> = [
                Layer::Transmission,
                Layer::Reflection,
                Layer::Strength,
                Layer::Mask,
                Layer::Depth,
            ]
            .into_iter()
            .map(|l| Ok((l, frame.read_layer(&ctx, l)?)))
            .collect::<Result<_>>()?;
            let named: Vec<(&str, &trgs_core::Image<f32>)> =
                layers.iter().map(|(l, img)| (l.name(), img)).collect();
            write_exr(&args.out.join(format!("{name}.exr")), &named)?;
        }
        bar.set_message(name);
        bar.inc(1);
    }
    bar.finish_and_clear();
    println!(
        "rendered {} views in {:.1} s ({:.1} views/s) to {}",
        cams.len(),
        t.elapsed().as_secs_f64(),
        cams.len() as f64 / t.elapsed().as_secs_f64(),
        args.out.display()
    );
    Ok(())
}
