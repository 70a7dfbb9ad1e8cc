//! The run folder belongs to one run at a time: [`RunLock`] holds it for the run's life, a new
//! run first sets a previous run's files aside ([`set_aside_previous_run`]), and the
//! unfinished-run marker (`trgs_core::io::run_folder`) tells every reader that the folder's
//! results are not written yet.
use anyhow::{Context, Result, bail};
use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, SystemTime};
use trgs_core::io::UNFINISHED_RUN_MARKER;

/// The lock file in a run folder. The operating system's lock on it (released on any exit, a
/// kill -9 included) is what holds the folder; the text in it names the holder for the message
/// that refuses a second run.
pub const LOCK_FILE: &str = "run.lock";

/// What a run writes into its folder, set aside whole when a new run starts there: its results,
/// its checkpoint and log, what `eval` wrote beside them, and the marker of an unfinished run.
/// (Temporaries of these that a kill left are removed when a run starts.) Every other file
/// `eval` names by what it measured is set aside too ([`is_eval_file`]).
pub(super) const RUN_FILES: [&str; 11] = [
    super::checkpoint::CHECKPOINT_FILE,
    super::log::LOG_FILE,
    "metrics.json",
    "exposures.json",
    "model.ply",
    "planes.json",
    "cameras.json",
    "renders",
    "eval.json",
    "eval_train.json",
    UNFINISHED_RUN_MARKER,
];

/// How often a run's lock file is marked alive while the run holds it (a thread of its own, so
/// that loading the photos or a long evaluation does not fall silent).
const BEAT: Duration = Duration::from_secs(60);

/// A holder on another host whose lock file has not been marked alive for this long has died
/// (a killed process clears nothing): only read where the file system has no locks.
const STALE_AFTER: Duration = Duration::from_secs(10 * 60);

/// Whether `name` is one of the files `eval` writes into a run folder: eval.json, or eval_ and
/// what it measured, .json.
fn is_eval_file(name: &str) -> bool {
    name == "eval.json" || (name.starts_with("eval_") && name.ends_with(".json"))
}

/// The folder of a run, held while the value lives (see the module docs).
#[derive(Debug)]
pub struct RunLock {
    file: File,
    /// Dropped with the lock: the thread that marks the file alive then ends.
    _beating: Option<mpsc::Sender<()>>,
}

impl RunLock {
    /// Hold `out` (created if need be) for this process, or say which run holds it.
    pub fn acquire(out: &Path) -> Result<Self> {
        std::fs::create_dir_all(out)
            .with_context(|| format!("creating the output folder {}", out.display()))?;
        let path = out.join(LOCK_FILE);
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .with_context(|| format!("opening the run folder's lock {}", path.display()))?;
        match file.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                bail!(held_by_another_run(out, &read_holder(&mut file)))
            }
            // A file system without locks (some network shares): the holder's pid and host
            // stand in for the operating system's lock.
            Err(TryLockError::Error(e)) if e.kind() == std::io::ErrorKind::Unsupported => {
                let holder = read_holder(&mut file);
                let quiet = file
                    .metadata()
                    .and_then(|m| m.modified())
                    .ok()
                    .map(|t| SystemTime::now().duration_since(t).unwrap_or(Duration::ZERO));
                if Holder::parse(&holder).is_some_and(|h| h.may_be_running(quiet)) {
                    bail!(
                        "{}; if no run is using it, delete {}",
                        held_by_another_run(out, &holder),
                        path.display()
                    );
                }
            }
            Err(TryLockError::Error(e)) => {
                return Err(e).with_context(|| format!("locking {}", path.display()));
            }
        }
        let me = Holder::this_process().line();
        file.set_len(0)
            .and_then(|()| file.rewind())
            .and_then(|()| file.write_all(me.as_bytes()))
            .and_then(|()| file.flush())
            .with_context(|| format!("writing {}", path.display()))?;
        Ok(Self { _beating: beat(&path, BEAT), file })
    }
}

/// Mark the file at `path` alive (its modification time) every `every` until the returned
/// sender is dropped: where the file system has no locks, a holder on another host silent for
/// [`STALE_AFTER`] is taken for dead, so that a retry on another node can take over a killed
/// run's folder. The file is opened anew at each beat: a handle kept by the thread (a
/// duplicate of the lock's) would hold the OS lock until the thread noticed the lock was gone.
/// Best effort: without a thread, or where the time cannot be set, only that takeover is lost.
fn beat(path: &Path, every: Duration) -> Option<mpsc::Sender<()>> {
    let path = path.to_path_buf();
    let (stop, stopped) = mpsc::channel::<()>();
    std::thread::Builder::new()
        .name("trgs-run-lock".into())
        .spawn(move || {
            while let Err(mpsc::RecvTimeoutError::Timeout) = stopped.recv_timeout(every) {
                let file = OpenOptions::new().write(true).open(&path);
                let _ = file.and_then(|f| f.set_modified(SystemTime::now()));
            }
        })
        .ok()?;
    Some(stop)
}

impl Drop for RunLock {
    fn drop(&mut self) {
        // The holder's line is cleared; the file stays, as removing it would let a run that
        // opened it just before lock a file no other run can see. The operating system's lock
        // goes with the file handle.
        let _ = self.file.set_len(0);
    }
}

/// Remove the folder `out` if it holds nothing but its lock file (a run refused before it
/// wrote anything); best effort.
pub fn remove_if_only_the_lock(out: &Path) {
    let only_lock = std::fs::read_dir(out)
        .map(|entries| entries.flatten().all(|e| e.file_name() == LOCK_FILE))
        .unwrap_or(false);
    if only_lock {
        let _ = std::fs::remove_file(out.join(LOCK_FILE));
        let _ = std::fs::remove_dir(out);
    }
}

/// The lock file's text (empty when it cannot be read).
fn read_holder(file: &mut File) -> String {
    let mut text = String::new();
    let _ = file.rewind().and_then(|()| file.read_to_string(&mut text));
    text
}

fn held_by_another_run(out: &Path, holder: &str) -> String {
    let who = match Holder::parse(holder) {
        Some(h) => format!(" (process {} on {})", h.pid, h.host),
        None => String::new(),
    };
    format!(
        "{} is in use by another training run{who}: two runs in one folder would mix their \
         files; wait for it to end or choose another --out",
        out.display()
    )
}

/// The process that holds a run folder, as its lock file names it: `pid host`.
#[derive(Debug, PartialEq)]
struct Holder {
    pid: u32,
    host: String,
}

impl Holder {
    fn this_process() -> Self {
        Self { pid: std::process::id(), host: host_name() }
    }

    fn line(&self) -> String {
        format!("{} {}\n", self.pid, self.host)
    }

    fn parse(text: &str) -> Option<Self> {
        let (pid, host) = text.trim().split_once(' ')?;
        Some(Self { pid: pid.parse().ok()?, host: host.to_string() })
    }

    /// Whether the process may still be running: on this host, whether it is (where the
    /// system says: /proc); on another host, whether it marked the lock file alive in the
    /// last [`STALE_AFTER`] (`quiet`: how long ago it did; None where that cannot be told).
    fn may_be_running(&self, quiet: Option<Duration>) -> bool {
        if self.host != host_name() {
            return quiet.is_none_or(|q| q < STALE_AFTER);
        }
        if self.pid == std::process::id() {
            return false;
        }
        let proc = Path::new("/proc");
        !proc.is_dir() || proc.join(self.pid.to_string()).exists()
    }
}

fn host_name() -> String {
    gethostname::gethostname().to_string_lossy().replace(char::is_whitespace, "_")
}

/// Move the files of a previous run in `out` into a new folder `out/previous-<n>` (the first
/// free n), so that nothing of it passes as this run's and nothing is lost; returns that folder
/// and the names moved, or None when there was nothing to move.
pub fn set_aside_previous_run(out: &Path) -> Result<Option<(PathBuf, Vec<String>)>> {
    let mut present: Vec<String> = RUN_FILES
        .into_iter()
        .filter(|f| out.join(f).symlink_metadata().is_ok())
        .map(String::from)
        .collect();
    // `eval` names its files by what it measured (eval_train_no-planes.json, ...).
    let mut evals: Vec<String> = std::fs::read_dir(out)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| is_eval_file(n) && !present.contains(n))
        .collect();
    evals.sort();
    present.extend(evals);
    if present.is_empty() {
        return Ok(None);
    }
    let aside = (1..)
        .map(|n| out.join(format!("previous-{n}")))
        .find(|p| p.symlink_metadata().is_err())
        .context("no free name for the previous run's files")?;
    std::fs::create_dir(&aside)
        .with_context(|| format!("creating {} for the previous run's files", aside.display()))?;
    for name in &present {
        std::fs::rename(out.join(name), aside.join(name)).with_context(|| {
            format!("moving {} into {}", out.join(name).display(), aside.display())
        })?;
    }
    Ok(Some((aside, present)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use trgs_core::scratch::ScratchDir;

    #[test]
    fn a_held_folder_is_refused_until_its_lock_is_dropped() {
        let dir = ScratchDir::new("run-lock");
        let out = dir.join("run");
        let held = RunLock::acquire(&out).expect("first");
        let text = std::fs::read_to_string(out.join(LOCK_FILE)).expect("lock file");
        assert_eq!(Holder::parse(&text), Some(Holder::this_process()));
        let err = RunLock::acquire(&out).expect_err("second").to_string();
        assert!(err.contains("in use by another training run"), "{err}");
        assert!(err.contains(&format!("process {}", std::process::id())), "{err}");
        drop(held);
        let again = RunLock::acquire(&out).expect("free again");
        drop(again);
    }

    #[test]
    fn a_stale_holder_is_told_apart_by_pid_and_host() {
        let me = Holder::this_process();
        let just_now = Some(Duration::from_secs(5));
        assert!(!me.may_be_running(just_now), "this process's own stale line");
        let elsewhere = Holder { pid: 1, host: format!("{}-other", me.host) };
        assert!(elsewhere.may_be_running(just_now), "another host, alive a moment ago");
        assert!(elsewhere.may_be_running(None), "another host, no time: no telling");
        assert!(!elsewhere.may_be_running(Some(STALE_AFTER)), "another host, silent: dead");
        if Path::new("/proc").is_dir() {
            // pid_max is at most 2^22 on Linux.
            let gone = Holder { pid: u32::MAX - 1, host: me.host.clone() };
            assert!(!gone.may_be_running(just_now));
        }
        assert_eq!(Holder::parse("garbage"), None);
    }

    #[test]
    fn the_lock_file_is_marked_alive_until_the_lock_goes() {
        let dir = ScratchDir::new("run-lock-beat");
        let path = dir.join(LOCK_FILE);
        let file =
            OpenOptions::new().read(true).write(true).create(true).truncate(false).open(&path);
        let file = file.expect("lock file");
        let long_ago = SystemTime::UNIX_EPOCH + Duration::from_secs(1_000_000);
        file.set_modified(long_ago).expect("set the time");
        let beating = beat(&path, Duration::from_millis(10)).expect("a thread");
        std::thread::sleep(Duration::from_millis(200));
        let touched = std::fs::metadata(&path).and_then(|m| m.modified()).expect("time");
        assert!(touched > long_ago + Duration::from_secs(1_000_000_000), "{touched:?}");
        drop(beating);
        std::thread::sleep(Duration::from_millis(50));
        file.set_modified(long_ago).expect("set the time");
        std::thread::sleep(Duration::from_millis(100));
        let after = std::fs::metadata(&path).and_then(|m| m.modified()).expect("time");
        assert_eq!(after, long_ago, "no beat after the lock went");
    }

    #[test]
    fn a_previous_run_is_set_aside_whole() {
        let dir = ScratchDir::new("run-set-aside");
        let out = dir.join("run");
        assert_eq!(set_aside_previous_run(&dir.join("none")).expect("no folder"), None);
        std::fs::create_dir_all(out.join("renders")).expect("renders");
        std::fs::create_dir_all(out.join("dataset")).expect("dataset");
        for f in ["model.ply", "metrics.json", "exposures.json", "log.jsonl", "eval_all.json"] {
            std::fs::write(out.join(f), f).expect("file");
        }
        let (aside, moved) = set_aside_previous_run(&out).expect("set aside").expect("moved");
        assert_eq!(aside, out.join("previous-1"));
        assert_eq!(
            moved,
            [
                "log.jsonl",
                "metrics.json",
                "exposures.json",
                "model.ply",
                "renders",
                "eval_all.json"
            ]
        );
        assert!(out.join("dataset").is_dir(), "the dataset is the run's input, not its output");
        assert!(!out.join("model.ply").exists());
        assert_eq!(std::fs::read_to_string(aside.join("model.ply")).expect("kept"), "model.ply");
        std::fs::write(out.join("model.ply"), "second").expect("file");
        let (aside, _) = set_aside_previous_run(&out).expect("again").expect("moved");
        assert_eq!(aside, out.join("previous-2"), "an earlier set-aside is kept");
    }
}
