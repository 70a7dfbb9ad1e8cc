//! `viewer [MODEL] [OPTIONS]`: the trgs viewer (see `viewer --help`).
use anyhow::{Context, Result, bail};
use std::path::PathBuf;
use trgs_render::Layer;
use trgs_viewer::{Script, Source, ViewerOptions, load_for_viewer};

const HELP: &str = "\
trgs viewer: real-time rendering of trained TR-Gaussians and 3DGS models

USAGE:
    viewer [MODEL] [OPTIONS]

MODEL is a run folder (model.ply, planes.json, cameras.json), a .ply (any INRIA-layout 3DGS
file; planes.json and cameras.json beside it are used) or a .glb (KHR_gaussian_splatting).
Without one, open a model from the window (Open…, or drop a file on it).

OPTIONS:
    --view N            start from dataset view N of cameras.json (default 0)
    --layer NAME        color (default), transmission, reflection, strength, strength_raw, mask,
                        depth or alpha
    --size WxH          window size in points (default 1100x700)
    --no-overlays       start with the plane overlays off
    --scale N           render at 1/N of the window's pixels: 1 (default), 2 or 4
    --screenshot PNG    save a screenshot (and PNG's .json: scene rectangle and camera) once drawn
    --frames N          re-render every frame and print the mean render and frame times of N
    --exit              close after --screenshot / --frames (scripts and tests)
    -h, --help          this text

CONTROLS:
    orbit mode: left drag orbits, right or middle drag pans, the wheel zooms
    fly mode: left drag looks around
    both: W/A/S/D move, Q/E move down/up, shift moves faster; F12 saves a screenshot
";

fn parse() -> Result<Option<ViewerOptions>> {
    let mut o = ViewerOptions::default();
    let mut model: Option<PathBuf> = None;
    let mut args = std::env::args().skip(1);
    let mut script = Script::default();
    while let Some(a) = args.next() {
        let mut value = |name: &str| args.next().with_context(|| format!("{name} needs a value"));
        match a.as_str() {
            "-h" | "--help" => return Ok(None),
            "--view" => o.view = Some(value("--view")?.parse().context("--view: a number")?),
            "--layer" => {
                let v = value("--layer")?;
                // The viewer does not render the depth-variance layer (only L_d needs it).
                let offered = || Layer::ALL.into_iter().filter(|&l| l != Layer::DepthVariance);
                o.layer = offered().find(|l| l.name() == v).with_context(|| {
                    let names: Vec<_> = offered().map(|l| l.name()).collect();
                    format!("--layer {v}: expected one of {}", names.join(", "))
                })?;
            }
            "--size" => {
                let v = value("--size")?;
                let (w, h) = v.split_once('x').context("--size: expected WxH, e.g. 800x600")?;
                o.window =
                    [w.parse().context("--size: width")?, h.parse().context("--size: height")?];
                if !o.window.iter().all(|&d| d.is_finite() && d >= 1.0) {
                    bail!("--size {v}: width and height must be at least 1");
                }
            }
            "--no-overlays" => o.overlays = false,
            "--scale" => {
                let v = value("--scale")?;
                o.scale = match v.as_str() {
                    "1" => 1,
                    "2" => 2,
                    "4" => 4,
                    _ => bail!("--scale {v}: expected 1, 2 or 4"),
                };
            }
            "--screenshot" => script.screenshot = Some(value("--screenshot")?.into()),
            "--frames" => {
                let v = value("--frames")?;
                let n = v.parse().ok().filter(|&n| n >= 1);
                script.frames =
                    Some(n.with_context(|| format!("--frames {v}: a count of 1 or more"))?);
            }
            "--exit" => script.exit = true,
            s if s.starts_with('-') => bail!("unknown option {s} (see --help)"),
            s => {
                if model.replace(PathBuf::from(s)).is_some() {
                    bail!("one model at a time (got a second: {s})");
                }
            }
        }
    }
    o.script = script;
    o.source = match model {
        Some(p) => {
            let m = load_for_viewer(&p)?;
            if let Some(v) = o.view
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
        None if o.view.is_some() => bail!("--view needs a model with a cameras.json"),
        // With nothing to draw, a scripted run would wait for a frame for ever.
        None if o.script.screenshot.is_some() || o.script.frames.is_some() => {
            bail!("--screenshot and --frames need a model")
        }
        None => Source::Nothing,
    };
    Ok(Some(o))
}

fn main() -> Result<()> {
    match parse()? {
        None => {
            print!("{HELP}");
            Ok(())
        }
        Some(options) => trgs_viewer::run(options),
    }
}
