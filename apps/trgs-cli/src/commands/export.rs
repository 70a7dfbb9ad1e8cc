//! `export`: a model for other viewers and back. By default a model with planes is baked
//! (`trgs_core::bake`) into plain Gaussians that any 3DGS viewer shows close to trgs's own
//! render; `--full` keeps the planes and the glass for trgs (a .ply with planes.json beside it,
//! or a .glb with the planes as nodes). The baked model's plain render is measured against trgs's
//! render on the model's views and the figure printed.
use anyhow::{Context, Result, bail};
use clap::Parser;
use std::path::{Path, PathBuf};
use trgs_core::io::{read_cameras_json, write_glb, write_planes_json, write_ply};
use trgs_core::{Camera, Gaussians};
use trgs_render::GpuContext;
use trgs_train::bake::{
    MEASURED_VIEWS, STRENGTH_LONG_SIDE, at_most, bake_for_plain_viewers, plain_render_psnr, spread,
    upload_model,
};
use trgs_train::model::{Model, load_model};

/// A model for any 3DGS viewer (.ply, .glb, .spz), or for trgs with its planes (--full).
///
/// A model with planes is baked by default: its glass Gaussians are left out, what each plane
/// reflects is added as mirrored Gaussians behind it, weighted by the strength its views see,
/// and what is seen through the glass is dimmed as the glass dims it; plain 3DGS renderers
/// (SuperSplat, Spark, Brush, SIBR, Cesium) then show the model close to trgs's own render.
/// The figure printed is the PSNR of a plain render of the output against trgs's render over
/// up to 16 of the model's views (at most 512 pixels long); `trgs eval --model OUT --reference
/// RUN` scores the test views. A model without planes is written as it is, less any glass
/// Gaussians (a model.ply copied without its planes.json).
#[derive(Debug, Parser)]
#[command(
    name = "export",
    version,
    after_help = "Which file for which viewer: the baked .ply, .glb or .spz for any 3DGS viewer; \
                  --full .ply (with planes.json) or .glb for trgs view, trgs render and trgs eval."
)]
pub struct Args {
    /// A run folder of `train`, a .ply (trgs or any INRIA-layout 3DGS PLY), a .glb or a .spz
    model: PathBuf,
    /// The file to write: .ply (INRIA layout), .glb (KHR_gaussian_splatting) or .spz (Niantic's
    /// compressed splats)
    out: PathBuf,
    /// Keep the planes and glass Gaussians (trgs's own model, for trgs's viewer and renderer):
    /// a .ply gets its planes.json beside it, a .glb holds them
    #[arg(long)]
    full: bool,
    /// The planes.json of MODEL [default: beside the PLY or in the run folder]
    #[arg(long, value_name = "FILE")]
    planes: Option<PathBuf>,
    /// The views the bake samples the glass from: a cameras.json [default: the run folder's or
    /// the one beside the model]
    #[arg(long, value_name = "FILE")]
    cameras: Option<PathBuf>,
}

/// The output's format, from its extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ply,
    Glb,
    Spz,
}

fn format_of(out: &Path) -> Result<Format> {
    let extension = out.extension().map(|e| e.to_string_lossy().to_lowercase());
    Ok(match extension.as_deref() {
        Some("ply") => Format::Ply,
        Some("glb") => Format::Glb,
        Some("spz") => Format::Spz,
        _ => bail!("{}: the output must end in .ply, .glb or .spz", out.display()),
    })
}

pub fn run(matches: &clap::ArgMatches) -> Result<()> {
    let args = super::parsed::<Args>(matches);
    let format = format_of(&args.out)?;
    if args.full && format == Format::Spz {
        bail!("--full keeps the planes, which .spz cannot hold: write a .ply or a .glb");
    }
    let model = load_model(&args.model, args.planes.as_deref())?;
    if args.full {
        return write_as_is(&model, &model.gaussians, &args.out, format);
    }
    let glass = model.gaussians.populations.iter().any(|&p| p != trgs_core::Population::Primary);
    if (glass || !model.planes.is_empty()) && is_same_file(&args.out, &model.ply) {
        bail!(
            "{}: the output is the model itself, which this export would replace with its glass \
             left out: write to another file",
            args.out.display()
        );
    }
    if model.planes.is_empty() {
        return write_without_planes(&model, &args.out, format);
    }
    let cameras = views_of(&args, &model)?;
    let ctx = GpuContext::new()?;
    let scene = upload_model(&ctx, &model)?;
    let (baked, report) = bake_for_plain_viewers(&ctx, &model, &scene, &cameras)?;
    write_gaussians(&args.out, format, &baked)?;
    let mirrored: Vec<String> = report
        .mirrored
        .iter()
        .enumerate()
        .map(|(k, n)| format!("{n} for plane {}", k + 1))
        .collect();
    println!(
        "{} baked for plain 3DGS viewers to {}: {} Gaussians; {} glass Gaussians left out, {} \
         seen through glass dimmed, mirrored copies added ({}), {} not seen in a reflection",
        model.ply.display(),
        args.out.display(),
        baked.len(),
        report.glass_left_out,
        report.dimmed,
        mirrored.join(", "),
        report.not_seen_mirrored
    );
    // A check, not the evaluation (`trgs eval --reference` scores the test views): a spread of
    // the views, at most 512 pixels long.
    let measured: Vec<Camera> =
        spread(&cameras, MEASURED_VIEWS).iter().map(|c| at_most(c, STRENGTH_LONG_SIDE)).collect();
    let scores = plain_render_psnr(&ctx, &model, &scene, &[&baked, &model.gaussians], &measured)?;
    let (baked_psnr, unbaked_psnr) = (scores[0], scores[1]);
    println!(
        "a plain 3DGS render of it against trgs's render: PSNR {baked_psnr:.2} dB over {} of \
         the {} (the model unbaked: {unbaked_psnr:.2} dB)",
        measured.len(),
        crate::wording::count(cameras.len(), "view")
    );
    Ok(())
}

/// The views the bake samples: `--cameras`, or the cameras.json of the run folder or beside
/// the model.
fn views_of(args: &Args, model: &Model) -> Result<Vec<Camera>> {
    let candidates = [args.model.join("cameras.json"), model.ply.with_file_name("cameras.json")];
    // A file given by name is read as it is, so that a missing one is named as such.
    let path = match &args.cameras {
        Some(given) => given.clone(),
        None => match candidates.into_iter().find(|p| p.is_file()) {
            Some(found) => found,
            None => bail!(
                "{}: baking its planes needs the views they were trained from, and there is no \
                 cameras.json in the run folder or beside the model: give --cameras FILE, or \
                 --full to keep the planes for trgs's own viewer",
                args.model.display()
            ),
        },
    };
    let cameras = read_cameras_json(&path)?;
    if cameras.is_empty() {
        bail!("{}: no views to bake from", path.display());
    }
    Ok(cameras)
}

/// Whether `a` and `b` name one existing file.
fn is_same_file(a: &Path, b: &Path) -> bool {
    matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
}

/// A model without planes for plain viewers: as it is, but for glass Gaussians (a model.ply
/// copied without its planes.json), which only trgs's mask reads and a plain viewer would draw
/// as an opaque slab: they are left out, as a bake leaves them out.
fn write_without_planes(m: &Model, out: &Path, format: Format) -> Result<()> {
    if m.gaussians.populations.iter().all(|&p| p == trgs_core::Population::Primary) {
        return write_as_is(m, &m.gaussians, out, format);
    }
    let (plain, report) = trgs_core::bake::bake(&m.gaussians, &[], &[]);
    println!(
        "{} holds {} glass Gaussians but no planes (no planes.json beside it; --planes FILE gives \
         them): the glass is left out",
        m.ply.display(),
        report.glass_left_out,
    );
    write_as_is(m, &plain, out, format)
}

/// `g`, `m`'s Gaussians as they are (with `--full`) or without their glass, and `m`'s planes.
fn write_as_is(m: &Model, g: &Gaussians<f32>, out: &Path, format: Format) -> Result<()> {
    match format {
        Format::Glb => write_glb(out, g, &m.planes)?,
        Format::Ply => {
            write_ply(out, g)?;
            // A planes.json already beside OUT would be read as this model's planes: a model
            // without planes overwrites it with an empty list rather than inherit stale ones.
            let json = out.with_file_name("planes.json");
            if !m.planes.is_empty() || json.exists() {
                write_planes_json(&json, &m.planes)?;
            }
        }
        Format::Spz => write_gaussians(out, format, g)?,
    }
    let planes_beside = format == Format::Ply && out.with_file_name("planes.json").exists();
    println!(
        "{} Gaussians (SH degree {}) and {} from {} written to {}{}",
        g.len(),
        g.sh_degree,
        crate::wording::count(m.planes.len(), "plane"),
        m.ply.display(),
        out.display(),
        if planes_beside {
            format!(" (planes in {})", out.with_file_name("planes.json").display())
        } else {
            String::new()
        }
    );
    Ok(())
}

/// Plain Gaussians in `format`.
fn write_gaussians(out: &Path, format: Format, g: &Gaussians<f32>) -> Result<()> {
    match format {
        Format::Ply => write_ply(out, g)?,
        Format::Glb => write_glb(out, g, &[])?,
        Format::Spz => trgs_core::io::write_spz(out, g)
            .with_context(|| format!("writing {}", out.display()))?,
    }
    Ok(())
}
