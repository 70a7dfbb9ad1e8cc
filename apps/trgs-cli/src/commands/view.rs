//! `viewer [MODEL] [OPTIONS]`: the trgs viewer (see `viewer --help`).
use crate::args::parse_window_size;
use anyhow::{Result, bail};
use clap::Parser;
use std::path::PathBuf;
use trgs_render::Layer;
use trgs_viewer::{Script, Source, ViewerOptions, load_for_viewer};

/// Real-time rendering of trained TR-Gaussians and 3DGS models.
///
/// MODEL is a run folder (model.ply, planes.json, cameras.json), a .ply (any INRIA-layout 3DGS
/// file; planes.json and cameras.json beside it are used), a .glb (KHR_gaussian_splatting) or an
/// .spz (Niantic's compressed splats).
/// Without one, open a model from the window (Open..., or drop a file on it).
#[derive(Debug, Parser)]
#[command(
    name = "viewer",
    version,
    after_help = "Controls:\n  orbit mode: left drag orbits, right or middle drag pans, the wheel \
                  zooms\n  fly mode: left drag looks around\n  both: W/A/S/D move, Q/E move \
                  down/up, shift moves faster; F12 saves a screenshot"
)]
pub struct Args {
    /// The model to show
    model: Option<PathBuf>,
    /// Start from dataset view N of cameras.json
    #[arg(long, value_name = "N")]
    view: Option<usize>,
    /// The layer shown
    #[arg(long, value_name = "NAME", default_value = "color", value_parser = layer_parser())]
    layer: Layer,
    /// Window size in points
    #[arg(long, value_name = "WxH", default_value = "1100x700", value_parser = parse_window_size)]
    size: [f32; 2],
    /// Start with the plane overlays off
    #[arg(long)]
    no_overlays: bool,
    /// Render at 1/N of the window's pixels
    #[arg(long, value_name = "N", default_value = "1",
          value_parser = clap::builder::PossibleValuesParser::new(["1", "2", "4"]))]
    scale: String,
    /// Save a screenshot (and PNG's .json: scene rectangle and camera) once drawn
    #[arg(long, value_name = "PNG")]
    screenshot: Option<PathBuf>,
    /// Re-render every frame and print the mean render and frame times of N frames
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    frames: Option<u32>,
    /// Close after --screenshot / --frames (scripts and tests)
    #[arg(long)]
    exit: bool,
}

/// The layers the viewer offers by name (not the depth variance, which only L_d needs).
fn layer_parser() -> impl clap::builder::TypedValueParser<Value = Layer> {
    use clap::builder::TypedValueParser as _;
    let offered = || Layer::ALL.into_iter().filter(|&l| l != Layer::DepthVariance);
    let names: Vec<&'static str> = offered().map(Layer::name).collect();
    clap::builder::PossibleValuesParser::new(names)
        .map(move |name| offered().find(|l| l.name() == name).unwrap_or(Layer::Color))
}

fn options(args: Args) -> Result<ViewerOptions> {
    let script = Script {
        screenshot: args.screenshot,
        frames: args.frames,
        exit: args.exit,
        ..Script::default()
    };
    let source = match &args.model {
        Some(p) => {
            let m = load_for_viewer(p)?;
            if let Some(v) = args.view
                && v >= m.cameras.len()
            {
                bail!(
                    "--view {v}: {} has {} dataset views (cameras.json beside the model)",
                    p.display(),
                    m.cameras.len()
                );
            }
            Source::Model(Box::new(m))
        }
        None if args.view.is_some() => bail!("--view needs a model with a cameras.json"),
        // With nothing to draw, a scripted run would wait for a frame for ever.
        None if script.screenshot.is_some() || script.frames.is_some() => {
            bail!("--screenshot and --frames need a model")
        }
        None => Source::Nothing,
    };
    Ok(ViewerOptions {
        source,
        window: args.size,
        view: args.view,
        layer: args.layer,
        overlays: !args.no_overlays,
        scale: args.scale.parse().unwrap_or(1),
        script,
    })
}

pub fn run(matches: &clap::ArgMatches) -> Result<()> {
    trgs_viewer::run(options(super::parsed::<Args>(matches))?)
}
