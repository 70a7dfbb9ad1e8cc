//! Scratch folders for tests and examples that write files: each is new and empty, unique to the
//! process and the call, and removed with everything in it when dropped, so that `cargo test`
//! leaves nothing behind in the temp folder. Set `TRGS_KEEP_SCRATCH=1` to keep them for a look.
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

static COUNTER: AtomicUsize = AtomicUsize::new(0);

/// An empty folder under the system temp folder, deleted on drop.
#[derive(Debug)]
pub struct ScratchDir {
    path: PathBuf,
}

impl ScratchDir {
    /// A new empty folder named after `tag`, the process and a per-process counter (tests run
    /// in parallel threads of one process).
    pub fn new(tag: &str) -> Self {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let path = std::env::temp_dir().join(format!("trgs-{tag}-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&path);
        std::fs::create_dir_all(&path)
            .unwrap_or_else(|e| panic!("cannot create the scratch folder {}: {e}", path.display()));
        Self { path }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl std::ops::Deref for ScratchDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for ScratchDir {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<std::ffi::OsStr> for ScratchDir {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.path.as_os_str()
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        if std::env::var_os("TRGS_KEEP_SCRATCH").is_none_or(|v| v.is_empty() || v == "0") {
            let _ = std::fs::remove_dir_all(&self.path);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn is_empty_unique_and_removed_on_drop() {
        let a = ScratchDir::new("scratch-test");
        let b = ScratchDir::new("scratch-test");
        assert_ne!(a.path(), b.path());
        std::fs::write(a.join("f.txt"), b"x").expect("write into the scratch folder");
        let kept = a.path().to_path_buf();
        assert!(kept.join("f.txt").is_file());
        if std::env::var_os("TRGS_KEEP_SCRATCH").is_none() {
            drop(a);
            assert!(!kept.exists(), "dropped scratch folder still exists");
        }
    }
}
