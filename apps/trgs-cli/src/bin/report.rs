//! `report`: speed against error of several training runs — their test PSNR after so many
//! seconds of training — as a Markdown table (printed) and a PNG plot.
use anyhow::{Context, Result, bail};
use std::path::PathBuf;
use trgs_cli::plot::{curve_of, markdown_table, plot};
use trgs_core::io::write_png_rgb;

const HELP: &str = "\
trgs report: test PSNR against training time of several runs

USAGE:
    report RUN_DIR... [--names A,B,...] [--plot FILE]

    Reads each run's metrics.json (psnr_over_time), prints a Markdown table and writes the plot
    (default psnr_vs_time.png).
";

fn main() -> Result<()> {
    let mut runs = Vec::new();
    let mut names: Option<Vec<String>> = None;
    let mut out = PathBuf::from("psnr_vs_time.png");
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        match a.as_str() {
            "-h" | "--help" => {
                print!("{HELP}");
                return Ok(());
            }
            "--names" => {
                let v = it.next().context("--names needs a value")?;
                names = Some(v.split(',').map(str::to_string).collect());
            }
            "--plot" => out = PathBuf::from(it.next().context("--plot needs a value")?),
            other if other.starts_with("--") => bail!("unknown option {other:?}\n\n{HELP}"),
            _ => runs.push(PathBuf::from(a)),
        }
    }
    if runs.is_empty() {
        bail!("no run folders given\n\n{HELP}");
    }
    if runs.len() > trgs_cli::plot::COLOURS.len() {
        bail!(
            "{} runs: at most {} fit one plot with a colour each",
            runs.len(),
            trgs_cli::plot::COLOURS.len()
        );
    }
    if let Some(n) = &names
        && n.len() != runs.len()
    {
        bail!("--names has {} names for {} runs", n.len(), runs.len());
    }
    let mut curves = Vec::new();
    for (i, run) in runs.iter().enumerate() {
        let path = run.join("metrics.json");
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("{}: cannot read the run's metrics", path.display()))?;
        let metrics: serde_json::Value =
            serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))?;
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
    write_png_rgb(&out, &plot(&curves, 640, 400))?;
    println!("plot written to {}", out.display());
    Ok(())
}
