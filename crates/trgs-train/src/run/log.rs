//! The run's JSONL log: one line per step and one per evaluation, appended as the run goes and
//! cut back to the checkpoint's step when a run resumes (so that every step is logged once).
use super::StepEvent;
use super::candidates::CandidateRecord;
use crate::eval::Evaluation;
use anyhow::{Context, Result};
use std::io::Write as _;
use std::path::{Path, PathBuf};
use trgs_core::io::write_atomic;

/// The log file's name in a run folder.
pub const LOG_FILE: &str = "log.jsonl";

/// An open log.
#[derive(Debug)]
pub struct RunLog {
    path: PathBuf,
    file: std::fs::File,
}

impl RunLog {
    /// A new, empty log in `dir`.
    pub fn create(dir: &Path) -> Result<Self> {
        let path = dir.join(LOG_FILE);
        std::fs::File::create(&path).with_context(|| format!("creating {}", path.display()))?;
        Self::open(dir)
    }

    /// The log in `dir` with the lines after step `step` removed (a resumed run writes them
    /// again).
    pub fn resume(dir: &Path, step: u32) -> Result<Self> {
        truncate(&dir.join(LOG_FILE), step)?;
        Self::open(dir)
    }

    fn open(dir: &Path) -> Result<Self> {
        let path = dir.join(LOG_FILE);
        let file = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&path)
            .with_context(|| format!("opening {}", path.display()))?;
        Ok(Self { path, file })
    }

    /// One step's line.
    pub fn step(&mut self, event: &StepEvent, seconds: f64) -> Result<()> {
        let StepEvent { step, view, gaussians, stats, memory, .. } = event;
        let phases: serde_json::Map<_, _> = stats
            .times
            .phases()
            .iter()
            .map(|(k, v)| (k.to_string(), serde_json::json!(v)))
            .collect();
        let gpu: Vec<_> = stats.gpu_stages.iter().map(|(k, v)| serde_json::json!([k, v])).collect();
        let line = serde_json::json!({"step": step, "view": view,
            "loss": stats.loss, "psnr": stats.psnr, "gaussians": gaussians, "keys": stats.keys,
            "seconds": seconds, "ms": phases, "gpu_ms": gpu, "perturbed": stats.perturbed,
            "skipped": stats.skipped, "record_waits": stats.record_waits,
            "gpu_bytes": memory.gpu.total(), "peak_ram_bytes": memory.peak_ram_bytes});
        self.line(&line)
    }

    /// One evaluation's line.
    pub fn evaluation(&mut self, e: &Evaluation) -> Result<()> {
        self.line(&serde_json::json!({"eval": e}))
    }

    /// The candidate planes of `--planes auto` as they stand after step `step` (proposed, then
    /// decided).
    pub fn candidates(&mut self, step: u32, records: &[CandidateRecord]) -> Result<()> {
        self.line(&serde_json::json!({"step": step, "candidates": records}))
    }

    fn line(&mut self, v: &serde_json::Value) -> Result<()> {
        writeln!(self.file, "{v}").with_context(|| format!("writing {}", self.path.display()))
    }

    /// Push what was written to the file (before a checkpoint names this point as safe).
    pub fn flush(&mut self) -> Result<()> {
        self.file.flush().with_context(|| format!("writing {}", self.path.display()))
    }
}

/// Keep the lines of `log` up to step `step`.
fn truncate(log: &Path, step: u32) -> Result<()> {
    let Ok(text) = std::fs::read_to_string(log) else { return Ok(()) };
    let keep: Vec<&str> = text
        .lines()
        .filter(|line| {
            let v: serde_json::Value = serde_json::from_str(line).unwrap_or_default();
            let s = v.get("step").or_else(|| v.get("eval").and_then(|e| e.get("step")));
            s.and_then(serde_json::Value::as_u64).is_some_and(|s| s <= u64::from(step))
        })
        .collect();
    let mut out = keep.join("\n");
    if !out.is_empty() {
        out.push('\n');
    }
    write_atomic(log, out.as_bytes())?;
    Ok(())
}
