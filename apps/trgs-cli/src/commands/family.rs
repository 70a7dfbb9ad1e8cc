//! `family`: TR-Gaussians against plain 3DGS on members of the synthetic scene family
//! (`trgs_synthetic::family`): each member's scene is generated once, both modes train on
//! it, and the table compares them against the truth: test PSNR overall, where the glass
//! reflects and elsewhere, the transmission layer against the true transmission, the planes and
//! their R0, and the training time. Interrupted runs resume; finished ones are read back.
use anyhow::{Context, Result, bail};
use clap::Parser;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use trgs_core::io::write_atomic;
use trgs_render::GpuContext;
use trgs_synthetic::family::{self, FamilyMember};
use trgs_train::eval::TruthComparison;
use trgs_train::{RunConfig, RunEvent, RunOptions, TrainingRun};

/// TR-Gaussians against plain 3DGS on members of the synthetic scene family: a table of PSNR
/// (overall, where the glass reflects and elsewhere, transmission against the
/// truth, planes, R0, time).
#[derive(Debug, Parser)]
#[command(name = "family", version)]
pub struct Args {
    /// Members: names of the fixed members, drawn-<SEED> for a member drawn from a seed, or
    /// `all` for the eight fixed members
    #[arg(long, value_name = "NAMES", value_delimiter = ',', default_value = "all")]
    members: Vec<String>,
    /// Training steps of every run
    #[arg(long, value_name = "N", default_value_t = 2000,
          value_parser = clap::value_parser!(u32).range(1..))]
    steps: u32,
    /// Folder of the scenes and runs: <OUT>/<member>/dataset, <OUT>/<member>/{tr,plain}-<steps>
    #[arg(long, value_name = "DIR", default_value = "runs/family")]
    out: PathBuf,
    /// Also write the table as Markdown
    #[arg(long, value_name = "FILE")]
    write: Option<PathBuf>,
    /// More `train` flags for the TR-Gaussians runs (an ablation or a variant), e.g.
    /// "--no-reflection-seeds"; their runs go to <OUT>/<member>/<--tr-label>-<steps>
    #[arg(long, value_name = "FLAGS", allow_hyphen_values = true, default_value = "")]
    tr_flags: String,
    /// Folder name of the TR-Gaussians runs
    #[arg(long, value_name = "NAME", default_value = "tr")]
    tr_label: String,
    /// List the members and what each tests, then exit
    #[arg(long)]
    list: bool,
}

/// What one finished run says, read back from its metrics.json.
#[derive(Clone, Debug, serde::Deserialize)]
struct Outcome {
    psnr: f64,
    train_seconds: f64,
    gaussians: u64,
    truth: Option<TruthComparison>,
}

pub fn run(matches: &clap::ArgMatches) -> Result<()> {
    let args = super::parsed::<Args>(matches);
    let members = resolve(&args.members)?;
    if args.list {
        for m in &members {
            println!("{:<20} {}", m.name, m.about);
        }
        return Ok(());
    }
    // Bad flags are refused before any scene is generated.
    let checked = RunConfig {
        data: Some(args.out.clone()),
        out: args.out.clone(),
        iterations: args.steps,
        ..run_config(&args.tr_flags)?
    };
    checked.check().with_context(|| format!("train flags {:?}", args.tr_flags))?;
    let ctx = GpuContext::new()?;
    let mut rows = Vec::new();
    for member in &members {
        let dir = args.out.join(&member.name);
        let data = scene_folder(member, &dir)?;
        let mut outcomes = Vec::new();
        for plain in [false, true] {
            let mode = if plain { "plain" } else { args.tr_label.as_str() };
            let out = dir.join(format!("{mode}-{}", args.steps));
            println!("{}: {mode}, {} steps -> {}", member.name, args.steps, out.display());
            let flags = if plain { "--no-planes" } else { args.tr_flags.as_str() };
            let config = RunConfig {
                data: Some(data.clone()),
                out: out.clone(),
                iterations: args.steps,
                ..run_config(flags)?
            };
            // What the run is: a folder that holds a run of other flags or of another scene is
            // trained again (the old run set aside by the new one), never read back as this.
            let made_by = format!("{flags}\n{}", describe(member));
            outcomes.push(train(&ctx, config, &made_by)?);
        }
        let plain = outcomes.pop().context("two runs")?;
        let tr = outcomes.pop().context("two runs")?;
        rows.push((member.clone(), tr, plain));
        // The table so far, so that a long series shows its progress.
        let table = table(&rows, args.steps);
        println!("{table}");
        write_atomic(&args.out.join("family.md"), table.as_bytes())?;
    }
    if let Some(path) = &args.write {
        write_atomic(path, table(&rows, args.steps).as_bytes())?;
        println!("table written to {}", path.display());
    }
    Ok(())
}

fn resolve(names: &[String]) -> Result<Vec<FamilyMember>> {
    let mut members = Vec::new();
    for name in names {
        if name == "all" {
            members.extend(family::members());
            continue;
        }
        match family::by_name(name) {
            Some(m) => members.push(m),
            None => {
                let known: Vec<String> = family::members().into_iter().map(|m| m.name).collect();
                bail!(
                    "--members: no member {name:?}; the members are {}, all, or drawn-<SEED>",
                    known.join(", ")
                );
            }
        }
    }
    Ok(members)
}

/// The member's scene folder, generated unless a folder of the same member is there.
fn scene_folder(member: &FamilyMember, dir: &Path) -> Result<PathBuf> {
    let data = dir.join("dataset");
    let marker = data.join("family_member.txt");
    let describe = describe(member);
    if std::fs::read_to_string(&marker).is_ok_and(|m| m == describe) {
        return Ok(data);
    }
    println!("{}: generating the scene ({})", member.name, member.about);
    // Written beside and renamed into place: a folder that exists is complete.
    let partial = dir.join("dataset.partial");
    for stale in [&partial, &data] {
        if stale.exists() {
            std::fs::remove_dir_all(stale)
                .with_context(|| format!("removing {}", stale.display()))?;
        }
    }
    member.write(&partial)?;
    write_atomic(&partial.join("family_member.txt"), describe.as_bytes())?;
    std::fs::rename(&partial, &data)
        .with_context(|| format!("renaming {} to {}", partial.display(), data.display()))?;
    Ok(data)
}

/// The member as its scene folder's marker records it.
fn describe(member: &FamilyMember) -> String {
    format!("{member:#?}\n")
}

/// The marker in a run folder of what made the run: its flags and its member.
const MADE_BY: &str = "family_run.txt";

/// `train`'s settings from its flags.
fn run_config(flags: &str) -> Result<RunConfig> {
    #[derive(Parser)]
    struct Flags {
        #[command(flatten)]
        config: RunConfig,
    }
    let argv = std::iter::once("train").chain(flags.split_whitespace());
    let parsed = Flags::try_parse_from(argv).with_context(|| format!("train flags {flags:?}"))?;
    Ok(parsed.config)
}

/// Options that run on `ctx`.
fn on(ctx: &GpuContext) -> RunOptions<'static> {
    RunOptions { context: Some(ctx.clone()), ..RunOptions::default() }
}

/// One run to its end (resumed from its checkpoint when interrupted, read back when finished),
/// `made_by` its flags and member: a run made by others starts anew.
fn train(ctx: &GpuContext, config: RunConfig, made_by: &str) -> Result<Outcome> {
    let out = config.out.clone();
    let metrics = out.join("metrics.json");
    let marker = out.join(MADE_BY);
    // Folders of older builds have no marker: taken as they are.
    let same = std::fs::read_to_string(&marker).map_or(true, |m| m == made_by);
    if !same {
        println!("  {} holds a run of other flags or another scene: training anew", out.display());
    }
    if !metrics.is_file() || !same {
        let resume = same && out.join("checkpoint.trgs").is_file();
        let mut run = if resume {
            TrainingRun::resume(&out, on(ctx))?
        } else {
            TrainingRun::start(config, on(ctx))?
        };
        // Only now: a start that failed before setting the old run aside leaves its marker.
        write_atomic(&marker, made_by.as_bytes())?;
        run.run_to_end(|event| match event {
            RunEvent::Evaluation(e) => {
                println!("  step {}: PSNR {:.2} dB ({:.0} s)", e.step, e.psnr, e.seconds)
            }
            RunEvent::PlaneFailed { label, reason } => println!("  plane {label}: {reason}"),
            _ => {}
        })?;
    }
    let text = std::fs::read_to_string(&metrics)
        .with_context(|| format!("reading {}", metrics.display()))?;
    serde_json::from_str(&text).with_context(|| format!("reading {}", metrics.display()))
}

/// A trained plane's R0, or "none" where no plane was trained for the true one (NaN).
fn fmt_r0(r0: f64) -> String {
    if r0.is_nan() { "none".into() } else { format!("{r0:.3}") }
}

fn fmt(v: Option<f64>) -> String {
    v.map_or("-".into(), |v| format!("{v:.2}"))
}

/// The comparison table in Markdown, with the issue's bars checked below it.
fn table(rows: &[(FamilyMember, Outcome, Outcome)], steps: u32) -> String {
    let mut s = format!(
        "TR-Gaussians (TR) against plain 3DGS at {steps} steps. PSNR in dB on the test views; \
         glass: where the glass shows a reflection, rest: elsewhere; T: the transmission layer \
         (plain 3DGS: its image) against the true transmission where the glass reflects.\n\n\
         | member | TR | plain | gain | glass TR / plain | rest TR / plain | T TR / plain | \
         T gain | planes (deg, % of size) | R0 (truth) | s TR / plain | Gaussians TR / plain |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|\n"
    );
    let mut gains = Vec::new();
    let mut t_gains = Vec::new();
    let mut rest_worst = f64::INFINITY;
    let mut plane_worst: (f64, f64) = (0.0, 0.0);
    let mut unfound = 0usize;
    for (m, tr, plain) in rows {
        let gain = tr.psnr - plain.psnr;
        gains.push(gain);
        let (tt, pt) = (tr.truth.as_ref(), plain.truth.as_ref());
        let pick =
            |t: Option<&TruthComparison>, f: fn(&TruthComparison) -> Option<f64>| t.and_then(f);
        let t_tr = pick(tt, |t| t.transmission_region_psnr);
        let t_plain = pick(pt, |t| t.transmission_region_psnr);
        let t_gain = t_tr.zip(t_plain).map(|(a, b)| a - b);
        t_gains.extend(t_gain);
        let rest = (pick(tt, |t| t.elsewhere_psnr), pick(pt, |t| t.elsewhere_psnr));
        if let (Some(a), Some(b)) = rest {
            rest_worst = rest_worst.min(a - b);
        }
        let planes: Vec<String> = tt
            .map(|t| {
                t.planes
                    .iter()
                    .map(|&(angle, centre)| {
                        // NaN: no trained plane for this true one (none was fitted); the bar
                        // then fails, as for a plane found far off.
                        if angle.is_nan() || centre.is_nan() {
                            unfound += 1;
                            return "none".to_string();
                        }
                        plane_worst = (plane_worst.0.max(angle), plane_worst.1.max(centre));
                        format!("{angle:.2}, {:.2}", 100.0 * centre)
                    })
                    .collect()
            })
            .unwrap_or_default();
        let r0: Vec<String> = tt
            .map(|t| t.r0.iter().map(|(a, b)| format!("{} ({b:.3})", fmt_r0(*a))).collect())
            .unwrap_or_default();
        let _ = writeln!(
            s,
            "| {} | {:.2} | {:.2} | {gain:+.2} | {} / {} | {} / {} | {} / {} | {} | {} | {} | \
             {:.0} / {:.0} | {} / {} |",
            m.name,
            tr.psnr,
            plain.psnr,
            fmt(pick(tt, |t| t.reflection_region_psnr)),
            fmt(pick(pt, |t| t.reflection_region_psnr)),
            fmt(rest.0),
            fmt(rest.1),
            fmt(t_tr),
            fmt(t_plain),
            t_gain.map_or("-".into(), |g| format!("{g:+.2}")),
            planes.join("; "),
            r0.join("; "),
            tr.train_seconds,
            plain.train_seconds,
            tr.gaussians,
            plain.gaussians,
        );
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let worst = gains.iter().copied().fold(f64::INFINITY, f64::min);
    let t_worst = t_gains.iter().copied().fold(f64::INFINITY, f64::min);
    let verdict = |ok: bool| if ok { "holds" } else { "FAILS" };
    let _ = write!(
        s,
        "\nOver {} members: mean gain {:+.2} dB (bar +1.00: {}), worst {:+.2} dB (bar -0.10: {}); \
         elsewhere worst {:+.2} dB (bar -0.10: {}); transmission mean gain {:+.2} dB (bar +3.00: \
         {}), worst {:+.2} dB (bar > 0: {}); planes worst {:.2} deg, {:.2}%{} (bar 2 deg, 2%: {}).\n",
        rows.len(),
        mean(&gains),
        verdict(mean(&gains) >= 1.0),
        worst,
        verdict(worst >= -0.1),
        rest_worst,
        verdict(rest_worst >= -0.1),
        mean(&t_gains),
        verdict(mean(&t_gains) >= 3.0),
        t_worst,
        verdict(t_worst > 0.0),
        plane_worst.0,
        100.0 * plane_worst.1,
        if unfound > 0 {
            format!(", {unfound} true plane(s) with none trained")
        } else {
            String::new()
        },
        verdict(unfound == 0 && plane_worst.0 <= 2.0 && plane_worst.1 <= 0.02),
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run whose truth comparison found no trained plane for the true one (NaN, as metrics.json
    /// writes it: null) reads "none" in the table and fails the planes bar.
    #[test]
    fn a_true_plane_without_a_trained_one_reads_none_and_fails_the_bar() {
        let outcome = |truth: &str| -> Outcome {
            serde_json::from_str(&format!(
                r#"{{"psnr": 30.0, "train_seconds": 1.0, "gaussians": 10, "truth": {truth}}}"#
            ))
            .expect("outcome")
        };
        let found =
            outcome(r#"{"planes": [[0.5, 0.01]], "r0": [[0.21, 0.2]], "transmission_psnr": 28.0}"#);
        let unfound = outcome(
            r#"{"planes": [[null, null]], "r0": [[null, 0.2]], "transmission_psnr": 28.0}"#,
        );
        let member = family::members().remove(0);
        let plain = outcome("null");
        let ok = table(&[(member.clone(), found, plain.clone())], 1);
        assert!(ok.contains("| 0.50, 1.00 |") && ok.contains("(bar 2 deg, 2%: holds)"), "{ok}");
        let bad = table(&[(member, unfound, plain)], 1);
        assert!(!bad.contains("NaN"), "{bad}");
        assert!(bad.contains("| none |") && bad.contains("none (0.200)"), "{bad}");
        assert!(bad.contains("1 true plane(s) with none trained (bar 2 deg, 2%: FAILS)"), "{bad}");
    }
}
