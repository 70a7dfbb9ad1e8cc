//! `report`: speed against error of several training runs — their test PSNR after so many
//! seconds of training — as a Markdown table (printed) and a PNG plot.
use crate::plot::{curve_of, markdown_table, plot};
use anyhow::{Result, bail};
use clap::Parser;
use std::path::PathBuf;
use trgs_core::io::write_png_rgb8;

/// Test PSNR against training time of several runs: reads each run's metrics.json
/// (psnr_over_time), prints a Markdown table and writes the plot.
#[derive(Debug, Parser)]
#[command(name = "report", version)]
pub struct Args {
    /// Run folders of `train`
    #[arg(required = true, value_name = "RUN_DIR")]
    runs: Vec<PathBuf>,
    /// The runs' names in the table and the legend, in order [default: their folders]
    #[arg(long, value_name = "A,B,...", value_delimiter = ',')]
    names: Option<Vec<String>>,
    /// The plot (PNG)
    #[arg(long, value_name = "FILE", default_value = "psnr_vs_time.png")]
    plot: PathBuf,
}

pub fn run(matches: &clap::ArgMatches) -> Result<()> {
    let Args { runs, names, plot: out } = super::parsed::<Args>(matches);
    if runs.len() > crate::plot::COLOURS.len() {
        bail!(
            "{} runs: at most {} fit one plot with a colour each",
            runs.len(),
            crate::plot::COLOURS.len()
        );
    }
    if let Some(n) = &names
        && n.len() != runs.len()
    {
        bail!("--names has {} names for {} runs", n.len(), runs.len());
    }
    let mut curves = Vec::new();
    for (i, run) in runs.iter().enumerate() {
        trgs_core::io::check_finished_run(run)?;
        let path = run.join("metrics.json");
        let metrics = trgs_core::io::RunMetrics::read(&path)?;
        let name = names
            .as_ref()
            .and_then(|n| n.get(i).cloned())
            .unwrap_or_else(|| run.display().to_string());
        let curve = curve_of(&name, &metrics);
        if curve.points.is_empty() {
            bail!("{}: no psnr_over_time entries", path.display());
        }
        curves.push(curve);
    }
    print!("{}", markdown_table(&curves));
    let image = plot(&curves, "Test PSNR against training time", 800, 500)?;
    write_png_rgb8(&out, &image)?;
    println!("plot written to {}", out.display());
    Ok(())
}
