//! What an unfinished `prepare` has done, kept in its work folder (`colmap/progress.txt`), so
//! that a rerun after a failure, a Ctrl-C or a change of flags starts from the first stage whose
//! inputs changed instead of extracting every feature again: a stage is done when the file holds
//! its line with the same key (the flags and inputs it depends on, and those of the stages before
//! it). The file also marks the folder as `prepare`'s own, which a rerun may clear.
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};
use trgs_core::io::write_atomic;

/// The stages whose work is kept between runs, in order.
pub const STAGES: [&str; 3] = ["photos", "features", "matching"];

/// The progress file of one scene folder.
#[derive(Debug)]
pub struct Progress {
    file: PathBuf,
    /// `(stage, key)` of the stages done, in order.
    done: Vec<(String, String)>,
}

impl Progress {
    /// The progress file in `work`, if an earlier run left one.
    pub fn load(work: &Path) -> Result<Option<Self>> {
        let file = work.join("progress.txt");
        if !file.is_file() {
            return Ok(None);
        }
        let text = std::fs::read_to_string(&file)
            .with_context(|| format!("reading {}", file.display()))?;
        let done = text
            .lines()
            .filter_map(|l| l.split_once('\t'))
            .filter(|(stage, _)| STAGES.contains(stage))
            .map(|(stage, key)| (stage.to_string(), key.to_string()))
            .collect();
        Ok(Some(Self { file, done }))
    }

    /// A new, empty progress file in `work` (written now: it marks the folder as ours before
    /// anything else is written there).
    pub fn start(work: &Path) -> Result<Self> {
        std::fs::create_dir_all(work).with_context(|| format!("creating {}", work.display()))?;
        let progress = Self { file: work.join("progress.txt"), done: Vec::new() };
        progress.save()?;
        Ok(progress)
    }

    /// Whether `stage` was done with `key` (and so every stage before it with theirs).
    pub fn is_done(&self, stage: &str, key: &str) -> bool {
        self.done.iter().any(|(s, k)| s == stage && k == key)
    }

    /// Record `stage` as done with `key`; the stages after it are forgotten (their inputs may
    /// have changed with it).
    pub fn record(&mut self, stage: &str, key: &str) -> Result<()> {
        let index = STAGES.iter().position(|s| *s == stage).unwrap_or(STAGES.len());
        self.done.retain(|(s, _)| STAGES.iter().position(|x| x == s).is_some_and(|i| i < index));
        self.done.push((stage.to_string(), key.to_string()));
        self.save()
    }

    /// Forget `stage` and those after it, before redoing it: a run stopped halfway leaves no
    /// line that claims the old work.
    pub fn forget_from(&mut self, stage: &str) -> Result<()> {
        let index = STAGES.iter().position(|s| *s == stage).unwrap_or(STAGES.len());
        self.done.retain(|(s, _)| STAGES.iter().position(|x| x == s).is_some_and(|i| i < index));
        self.save()
    }

    fn save(&self) -> Result<()> {
        let mut text =
            String::from("# prepare's progress: a rerun with the same flags skips these stages\n");
        for (stage, key) in &self.done {
            text += &format!("{stage}\t{key}\n");
        }
        Ok(write_atomic(&self.file, text.as_bytes())?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use trgs_core::scratch::ScratchDir;

    #[test]
    fn a_stage_redone_forgets_those_after_it_and_the_file_survives_a_reload() {
        let dir = ScratchDir::new("prepare-progress");
        assert!(Progress::load(&dir).expect("no file").is_none());
        let mut p = Progress::start(&dir).expect("start");
        p.record("photos", "a every 1").expect("photos");
        p.record("features", "SIMPLE_RADIAL").expect("features");
        p.record("matching", "exhaustive").expect("matching");
        let p2 = Progress::load(&dir).expect("read").expect("file");
        assert!(p2.is_done("features", "SIMPLE_RADIAL") && p2.is_done("matching", "exhaustive"));
        assert!(!p2.is_done("matching", "sequential"));
        p.record("features", "OPENCV").expect("features again");
        assert!(!p.is_done("matching", "exhaustive"), "matching depended on the features");
        assert!(p.is_done("photos", "a every 1"));
        p.forget_from("photos").expect("forget");
        let p3 = Progress::load(&dir).expect("read").expect("file");
        assert!(!p3.is_done("photos", "a every 1") && !p3.is_done("features", "OPENCV"));
    }
}
