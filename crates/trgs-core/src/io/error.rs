use std::path::{Path, PathBuf};

/// A malformed or unreadable input file: the file and what was wrong (with line or field).
#[derive(Debug, thiserror::Error)]
#[error("{}: {problem}", path.display())]
pub struct FormatError {
    pub path: PathBuf,
    pub problem: String,
}

impl FormatError {
    pub fn new(path: impl AsRef<Path>, problem: impl Into<String>) -> Self {
        Self { path: path.as_ref().to_path_buf(), problem: problem.into() }
    }

    /// An I/O error on `path`, e.g. a missing file.
    pub fn io(path: impl AsRef<Path>, err: &std::io::Error) -> Self {
        Self::new(path, err.to_string())
    }
}

/// Write `bytes` to `path` through a temporary file in the same folder and a rename, so that a
/// reader never sees a half-written file and an interrupted write leaves the old file intact.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), FormatError> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// [`write_atomic`] of what `write` writes, through a buffer: a large file (a checkpoint of
/// millions of Gaussians) need not be held in memory whole first.
pub fn write_atomic_with(
    path: &Path,
    write: impl FnOnce(&mut dyn std::io::Write) -> std::io::Result<()>,
) -> Result<(), FormatError> {
    use std::io::Write;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| FormatError::io(dir, &e))?;
    }
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    // Unique per process and per call, so that two threads writing one path never share it.
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let call = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let tmp = path.with_file_name(format!(".{name}.{}.{call}.tmp", std::process::id()));
    let result = (|| {
        let mut f = std::io::BufWriter::with_capacity(1 << 20, std::fs::File::create(&tmp)?);
        write(&mut f)?;
        f.flush()?;
        f.get_ref().sync_all()?;
        drop(f);
        std::fs::rename(&tmp, path)
    })();
    result.map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        FormatError::io(path, &e)
    })
}

/// Remove what writes of `files` (names in `dir`) cut short by a kill left behind: the
/// temporary files `write_atomic` names `.<file>.<pid>.<n>.tmp`. Best effort: a file that cannot
/// be removed stays.
pub fn remove_stale_temporaries(dir: &Path, files: &[&str]) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let ours = files.iter().any(|f| name.starts_with(&format!(".{f}.")));
        if ours && name.ends_with(".tmp") {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// The whole of `path`, or an error naming it (e.g. "No such file or directory").
pub(crate) fn read_bytes(path: &Path) -> Result<Vec<u8>, FormatError> {
    std::fs::read(path).map_err(|e| FormatError::io(path, &e))
}

/// The whole of `path` as UTF-8 text; invalid UTF-8 is an error naming the line it is on.
pub(crate) fn read_text(path: &Path) -> Result<String, FormatError> {
    let bytes = read_bytes(path)?;
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let line = 1 + e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count();
        FormatError::new(path, format!("line {line}: not valid UTF-8 text"))
    })
}
