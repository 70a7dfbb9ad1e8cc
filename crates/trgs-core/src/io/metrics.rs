//! The parts of a run's `metrics.json` that are read back by the tools after `train` (`eval`,
//! `report`, `merge`, the viewer, model loading), as types. `train` writes those parts from the
//! same types, so each field's name is in one place. The rest of the file (timings, memory,
//! the truth comparison) is written for people and scripts and read back by none of them.
use super::FormatError;
use crate::pipeline::ReflectionModel;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One evaluation of the test views (`psnr_over_time`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvaluationPoint {
    pub step: u32,
    /// Seconds of training steps up to it (not evaluating or writing checkpoints).
    pub seconds: f64,
    #[serde(deserialize_with = "psnr_or_exact")]
    pub psnr: f64,
    pub ssim: f64,
}

/// One test view's scores at the last evaluation (`views`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ViewScore {
    pub name: String,
    #[serde(deserialize_with = "psnr_or_exact")]
    pub psnr: f64,
    pub ssim: f64,
}

/// A PSNR as JSON holds it: a view rendered exactly has an infinite PSNR, which JSON cannot
/// hold and serde_json writes as null; read back, null is that infinity.
fn psnr_or_exact<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
}

/// Where a candidate plane of a `--planes auto` run lay and what became of it: the fields of
/// `trgs_train::CandidateRecord` (`candidates`) that outline it.
#[derive(Clone, Debug, PartialEq, Deserialize)]
pub struct CandidateOutline {
    pub centre: Option<[f64; 3]>,
    pub normal: Option<[f64; 3]>,
    /// In-plane, along the width.
    pub axis: Option<[f64; 3]>,
    pub size: Option<[f64; 2]>,
    pub proposed: bool,
    pub kept: bool,
}

/// What the tools after `train` read of a run's `metrics.json`. Every part is optional: a run
/// of an older build, a merged run and another tool's file hold some of them.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(default)]
pub struct RunMetrics {
    pub views: Vec<ViewScore>,
    pub psnr_over_time: Vec<EvaluationPoint>,
    /// The reflection model the run trained with (its ablations), which a renderer of the
    /// model must follow; a part the record leaves out is on.
    pub reflection_model: Option<ReflectionModel>,
    pub candidates: Vec<CandidateOutline>,
    /// A merged run's test views that look across a seam between blocks (`trgs merge`).
    pub seam_views: Option<Vec<String>>,
}

impl RunMetrics {
    pub fn parse(text: &str) -> Result<Self, serde_json::Error> {
        serde_json::from_str(text)
    }

    /// The metrics at `path`; an error names the file and what was expected.
    pub fn read(path: &Path) -> Result<Self, FormatError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| FormatError::new(path, format!("cannot read the run's metrics: {e}")))?;
        Self::parse(&text)
            .map_err(|e| FormatError::new(path, format!("not the metrics.json of a trgs run: {e}")))
    }

    /// The metrics at `path`, or none where the file is missing or is not one of trgs's: for
    /// readers to whom the record is a help, not a need (the viewer's outlines, a model's
    /// reflection model).
    pub fn read_if_any(path: &Path) -> Option<Self> {
        Self::parse(&std::fs::read_to_string(path).ok()?).ok()
    }

    /// The names of the test views of the last evaluation.
    pub fn test_view_names(&self) -> Vec<String> {
        self.views.iter().map(|v| v.name.clone()).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_of_an_older_build_or_another_tool_reads_with_what_it_has() {
        let m = RunMetrics::parse(r#"{"psnr": 30.5, "other": [1, 2]}"#).expect("metrics");
        assert!(m.views.is_empty() && m.psnr_over_time.is_empty() && m.candidates.is_empty());
        assert_eq!(m.reflection_model, None);
        assert_eq!(m.seam_views, None);
        let m = RunMetrics::parse(r#"{"reflection_model": {"fresnel": false}}"#).expect("metrics");
        assert_eq!(m.reflection_model, Some(ReflectionModel { fresnel: false, intensity: true }));
    }

    #[test]
    fn a_view_rendered_exactly_reads_back_with_an_infinite_psnr() {
        let exact = ViewScore { name: "a.png".into(), psnr: f64::INFINITY, ssim: 1.0 };
        let point = EvaluationPoint { step: 10, seconds: 1.5, psnr: f64::INFINITY, ssim: 1.0 };
        let text = serde_json::json!({"views": [exact], "psnr_over_time": [point]}).to_string();
        assert!(text.contains("null"), "{text}");
        let m = RunMetrics::parse(&text).expect("metrics");
        assert_eq!(m.views[0].psnr, f64::INFINITY);
        assert_eq!(m.psnr_over_time[0].psnr, f64::INFINITY);
        assert_eq!(m.test_view_names(), ["a.png"]);
    }

    #[test]
    fn a_field_of_the_wrong_kind_is_an_error_that_names_the_file() {
        let dir = crate::scratch::ScratchDir::new("metrics-wrong-kind");
        let path = dir.join("metrics.json");
        std::fs::write(&path, r#"{"psnr_over_time": 3}"#).expect("write");
        let e = RunMetrics::read(&path).expect_err("wrong kind").to_string();
        assert!(e.contains("metrics.json") && e.contains("not the metrics.json"), "{e}");
        assert_eq!(RunMetrics::read_if_any(&path), None);
        assert_eq!(RunMetrics::read_if_any(&dir.join("missing.json")), None);
    }
}
