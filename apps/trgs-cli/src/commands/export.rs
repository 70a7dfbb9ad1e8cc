//! `convert`: a model between trgs's formats: a run folder or .ply (with its planes.json) to a
//! .glb with `KHR_gaussian_splatting`, or a .glb back to model.ply and planes.json.
use anyhow::{Result, bail};
use clap::Parser;
use std::path::{Path, PathBuf};
use trgs_core::io::{write_glb, write_planes_json, write_ply};
use trgs_train::model::load_model;

/// A model to glTF (KHR_gaussian_splatting) or back to PLY.
#[derive(Debug, Parser)]
#[command(name = "convert", version)]
struct Args {
    /// A run folder of `train`, a .ply (trgs or any INRIA-layout 3DGS PLY) or a .glb
    model: PathBuf,
    /// A .glb: Gaussians and planes in one file (planes as nodes, every parameter in their
    /// extras); or a .ply: the Gaussians, with the planes in planes.json beside it
    out: PathBuf,
    /// The planes.json of MODEL [default: beside the PLY or in the run folder]
    #[arg(long, value_name = "FILE")]
    planes: Option<PathBuf>,
}

fn main() -> Result<()> {
    let Args { model, out, planes } = Args::parse();
    let (model, out) = (&model, &out);
    let m = load_model(model, planes.as_deref())?;
    let extension = out.extension().map(|e| e.to_string_lossy().to_lowercase());
    match extension.as_deref() {
        Some("glb") => write_glb(out, &m.gaussians, &m.planes)?,
        Some("ply") => {
            write_ply(out, &m.gaussians)?;
            // A planes.json already beside OUT would be read as this model's planes: a model
            // without planes overwrites it with an empty list rather than inherit stale ones.
            let json = out.with_file_name("planes.json");
            if !m.planes.is_empty() || json.exists() {
                write_planes_json(&json, &m.planes)?;
            }
        }
        _ => bail!("{}: the output must end in .glb or .ply", out.display()),
    }
    println!(
        "{} Gaussians (SH degree {}) and {} planes from {} written to {}",
        m.gaussians.len(),
        m.gaussians.sh_degree,
        m.planes.len(),
        m.ply.display(),
        display_with_planes(
            out,
            !m.planes.is_empty() || out.with_file_name("planes.json").exists()
        )
    );
    Ok(())
}

fn display_with_planes(out: &Path, planes: bool) -> String {
    let is_ply = out.extension().is_some_and(|e| e.eq_ignore_ascii_case("ply"));
    if is_ply && planes {
        format!("{} (planes in {})", out.display(), out.with_file_name("planes.json").display())
    } else {
        out.display().to_string()
    }
}
