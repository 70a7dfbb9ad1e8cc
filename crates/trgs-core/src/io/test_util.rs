//! Helpers for the format tests: scratch folders and error-message checks.
use crate::scratch::ScratchDir;

/// A new empty folder, unique to this process, call and `tag`, removed when dropped.
pub(crate) fn scratch_dir(tag: &str) -> ScratchDir {
    ScratchDir::new(&format!("io-{tag}"))
}

/// Assert that an error message mentions every one of `parts`.
#[track_caller]
pub(crate) fn assert_mentions(err: &impl std::fmt::Display, parts: &[&str]) {
    let msg = err.to_string();
    for p in parts {
        assert!(msg.contains(p), "error {msg:?} does not mention {p:?}");
    }
}
