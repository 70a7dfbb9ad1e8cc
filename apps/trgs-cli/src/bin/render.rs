//! `render`: render a model from the cameras of a dataset folder or a camera path, writing a PNG
//! of the final image per view and an OpenEXR of its linear layers (depth, strength,
//! transmission, reflection, mask), with a progress bar.
use anyhow::{Context, Result, anyhow, bail};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::time::Instant;
use trgs_cli::exr_layers::write_exr;
use trgs_core::io::{SceneFolder, Split, read_transforms, write_png_rgb};
use trgs_core::plane_math::{flip_horizontal, mirror_camera, mirrored_pass_gaussians};
use trgs_core::scene::Camera;
use trgs_render::{GpuContext, GpuScene, Layer, RenderOptions, Renderer};
use trgs_train::model::{Model, load_model};

const HELP: &str = "\
trgs render: render a model from a dataset's cameras or a camera path

USAGE:
    render --model PATH --cameras PATH [OPTIONS]

OPTIONS:
    --model PATH        a .ply (trgs or any INRIA-layout 3DGS PLY), a .glb
                        (KHR_gaussian_splatting, planes included), or a run folder holding
                        model.ply or point_cloud/iteration_*/point_cloud.ply
    --planes FILE       trained planes.json (default: planes.json beside the PLY or in the run
                        folder; none means no planes)
    --cameras PATH      a scene folder (COLMAP or transforms.json) or a transforms.json camera path
    --split SPLIT       with a scene folder: test (default), train or all
    --out DIR           output folder (default: renders)
    --background R,G,B  background colour in [0, 1] (default 0,0,0)
    --no-exr            only the PNGs
    --mirror N          instead, what plane N (1 = the first in planes.json) reflects: each
                        camera's mirrored view over the whole image, aligned with the camera's
                        pixels (inside the plane's rectangle it is the raw reflection C_raw
                        on the default black background),
                        written as <view>_mirror<N>.png; cameras behind the plane are skipped
    -h, --help          this text
";

struct Args {
    model: PathBuf,
    planes: Option<PathBuf>,
    cameras: PathBuf,
    split: Split,
    out: PathBuf,
    background: [f32; 3],
    exr: bool,
    mirror: Option<usize>,
}

fn parse_args() -> Result<Option<Args>> {
    let (mut model, mut cameras) = (None, None);
    let mut args = Args {
        model: PathBuf::new(),
        planes: None,
        cameras: PathBuf::new(),
        split: Split::Test,
        out: PathBuf::from("renders"),
        background: [0.0; 3],
        exr: true,
        mirror: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        let mut value = |name: &str| it.next().with_context(|| format!("{name} needs a value"));
        match a.as_str() {
            "-h" | "--help" => return Ok(None),
            "--model" => model = Some(PathBuf::from(value("--model")?)),
            "--planes" => args.planes = Some(PathBuf::from(value("--planes")?)),
            "--cameras" => cameras = Some(PathBuf::from(value("--cameras")?)),
            "--split" => {
                args.split = value("--split")?.parse().map_err(|e| anyhow!("--split {e}"))?
            }
            "--out" => args.out = PathBuf::from(value("--out")?),
            "--background" => {
                let v = value("--background")?;
                let parts: Vec<Option<f32>> = v
                    .split(',')
                    .map(|p| p.trim().parse().ok().filter(|x: &f32| (0.0..=1.0).contains(x)))
                    .collect();
                let [Some(r), Some(g), Some(b)] = parts[..] else {
                    bail!("--background {v:?}: expected three numbers in [0, 1], e.g. 1,1,1");
                };
                args.background = [r, g, b];
            }
            "--no-exr" => args.exr = false,
            "--mirror" => {
                let v = value("--mirror")?;
                let n = v.parse().ok().filter(|&n: &usize| n >= 1);
                args.mirror = Some(n.with_context(|| {
                    format!("--mirror {v:?}: expected a plane number, 1 or more")
                })?);
            }
            other => bail!("unknown argument {other:?}\n\n{HELP}"),
        }
    }
    args.model = model.with_context(|| format!("--model is required\n\n{HELP}"))?;
    args.cameras = cameras.with_context(|| format!("--cameras is required\n\n{HELP}"))?;
    Ok(Some(args))
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

fn main() -> Result<()> {
    let Some(args) = parse_args()? else {
        print!("{HELP}");
        return Ok(());
    };
    let model = load_model(&args.model, args.planes.as_deref())?;
    let cams = cameras(&args.cameras, args.split)?;
    if cams.is_empty() {
        bail!("{}: no cameras in the {} split", args.cameras.display(), args.split.name());
    }
    let ctx = GpuContext::new()?;
    println!(
        "{}: {} Gaussians (SH degree {}), {} planes; {} views on {}",
        model.ply.display(),
        model.gaussians.len(),
        model.gaussians.sh_degree,
        model.planes.len(),
        cams.len(),
        ctx.describe()
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
        return render_mirror(&args, &model, &cams, &renderer, &options, n);
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
        if args.exr {
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
