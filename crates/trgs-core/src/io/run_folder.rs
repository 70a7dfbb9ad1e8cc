//! What every reader of a training run's folder must know: whether the run in it has finished.
//! A run keeps [`UNFINISHED_RUN_MARKER`] in its folder from its start until its results are
//! written; a folder with the marker holds no results to use (a new run sets the previous run's
//! files aside first), so `eval`, `render`, the viewer and `report` refuse it by name instead of
//! reading what another run left.
use super::FormatError;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The file that marks a run folder's run as unfinished (running, or stopped before its end).
pub const UNFINISHED_RUN_MARKER: &str = "unfinished-run.json";

/// What the marker records: how far the run is, for the message that refuses its folder.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct UnfinishedRun {
    /// The run's planned steps.
    pub iterations: u32,
    /// The step of its last checkpoint (0: none yet).
    pub checkpoint_step: u32,
}

/// Mark `dir`'s run unfinished (written atomically: a reader sees the old record or the new).
pub fn write_unfinished_run(dir: &Path, run: &UnfinishedRun) -> Result<(), FormatError> {
    let path = dir.join(UNFINISHED_RUN_MARKER);
    let json = serde_json::to_string(run).map_err(|e| FormatError::new(&path, e.to_string()))?;
    super::write_atomic(&path, json.as_bytes())
}

/// What the marker in `dir` records, if there is one that can be read.
pub fn read_unfinished_run(dir: &Path) -> Option<UnfinishedRun> {
    let text = std::fs::read_to_string(dir.join(UNFINISHED_RUN_MARKER)).ok()?;
    serde_json::from_str(&text).ok()
}

/// Mark `dir`'s run finished (its results are written).
pub fn clear_unfinished_run(dir: &Path) -> Result<(), FormatError> {
    let path = dir.join(UNFINISHED_RUN_MARKER);
    match std::fs::remove_file(&path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(FormatError::io(&path, &e)),
        _ => Ok(()),
    }
}

/// Refuse the folder `dir` while its run is unfinished, saying how far it is and how to go on.
/// A folder without the marker (a finished run, another tool's output) passes.
pub fn check_finished_run(dir: &Path) -> Result<(), FormatError> {
    let path = dir.join(UNFINISHED_RUN_MARKER);
    let Ok(text) = std::fs::read_to_string(&path) else {
        // No marker; or one that cannot be read, which `symlink_metadata` tells apart.
        return match std::fs::symlink_metadata(&path) {
            Ok(_) => Err(FormatError::new(&path, "an unfinished run's marker that cannot be read")),
            Err(_) => Ok(()),
        };
    };
    let how_far = match serde_json::from_str::<UnfinishedRun>(&text) {
        Ok(r) if r.checkpoint_step > 0 => {
            format!("its last checkpoint is at step {} of {}", r.checkpoint_step, r.iterations)
        }
        Ok(r) => format!("it has no checkpoint yet of its {} steps", r.iterations),
        Err(_) => "its marker does not say how far it is".to_string(),
    };
    Err(FormatError::new(
        dir,
        format!(
            "an unfinished training run (still running, or stopped: {how_far}); its results are \
             written when it finishes, and `trgs train --out {} --resume` continues it",
            dir.display()
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_marked_folder_is_refused_until_the_run_finishes() {
        let dir = crate::scratch::ScratchDir::new("run-folder-marker");
        check_finished_run(&dir).expect("no marker: a finished run or another tool's folder");
        write_unfinished_run(&dir, &UnfinishedRun { iterations: 2000, checkpoint_step: 0 })
            .expect("mark");
        let err = check_finished_run(&dir).expect_err("unfinished").to_string();
        assert!(err.contains("unfinished training run") && err.contains("no checkpoint"), "{err}");
        write_unfinished_run(&dir, &UnfinishedRun { iterations: 2000, checkpoint_step: 400 })
            .expect("mark");
        let err = check_finished_run(&dir).expect_err("unfinished").to_string();
        assert!(err.contains("step 400 of 2000") && err.contains("--resume"), "{err}");
        assert_eq!(read_unfinished_run(&dir).map(|r| r.checkpoint_step), Some(400));
        clear_unfinished_run(&dir).expect("clear");
        clear_unfinished_run(&dir).expect("clearing twice is fine");
        check_finished_run(&dir).expect("finished");
    }
}
