//! Reading Rust source as the structure checks need it: the workspace's crates and their files,
//! each file's code without comments and string contents, and its comments apart.

use std::path::{Path, PathBuf};

/// The repository root (the facade crate's folder).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every file under `dir` (recursively) whose name ends with `ext`, sorted; `target/` and
/// hidden folders are skipped.
pub fn files_with(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else { continue };
        for entry in entries.flatten() {
            let path = entry.path();
            let name = entry.file_name().to_string_lossy().into_owned();
            if path.is_dir() {
                if !(name.starts_with('.') || name == "target" || name == "runs") {
                    stack.push(path);
                }
            } else if name.ends_with(ext) {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// One crate (a library or a binary): its root file and the folder its modules live in.
#[derive(Debug, Clone)]
pub struct CrateRoot {
    pub name: String,
    /// lib.rs or main.rs (or a bin's single file).
    pub root_file: PathBuf,
}

/// Every library and binary crate of the workspace: `src/lib.rs` of each package and each
/// binary under `src/bin/` (a file, or a folder with main.rs).
pub fn crates() -> Vec<CrateRoot> {
    let root = root();
    let mut packages = vec![root.clone(), root.join("apps/trgs-cli")];
    for entry in std::fs::read_dir(root.join("crates")).expect("crates/ exists").flatten() {
        packages.push(entry.path());
    }
    let mut out = Vec::new();
    for package in packages {
        let src = package.join("src");
        let name = package.file_name().unwrap_or_default().to_string_lossy().into_owned();
        if src.join("lib.rs").is_file() {
            out.push(CrateRoot { name: name.clone(), root_file: src.join("lib.rs") });
        }
        let Ok(bins) = std::fs::read_dir(src.join("bin")) else { continue };
        for bin in bins.flatten() {
            let path = bin.path();
            let stem = path.file_stem().unwrap_or_default().to_string_lossy().into_owned();
            let root_file = if path.is_dir() { path.join("main.rs") } else { path };
            out.push(CrateRoot { name: format!("{name}/bin/{stem}"), root_file });
        }
    }
    out.sort_by(|a, b| a.name.cmp(&b.name));
    out
}

/// A source file split into its code (comments removed; string and char literals emptied, so
/// that braces and `::` in them count for nothing) and its comments (doc comments included),
/// both keeping the file's line breaks.
#[derive(Debug)]
pub struct Split {
    pub code: String,
    pub comments: String,
}

/// Split `text` (Rust source) into code and comments.
pub fn split(text: &str) -> Split {
    let b = text.as_bytes();
    let (mut code, mut comments) = (String::new(), String::new());
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if c == b'/' && b.get(i + 1) == Some(&b'/') {
            let end = text[i..].find('\n').map_or(b.len(), |e| i + e);
            comments.push_str(&text[i..end]);
            i = end;
        } else if c == b'/' && b.get(i + 1) == Some(&b'*') {
            let end = text[i + 2..].find("*/").map_or(b.len(), |e| i + 2 + e + 2);
            let block = &text[i..end];
            comments.push_str(block);
            code.extend(block.chars().filter(|&ch| ch == '\n'));
            i = end;
        } else if c == b'"' || (c == b'r' && raw_string_start(b, i).is_some()) {
            let end = string_end(b, i);
            code.push_str("\"\"");
            code.extend(text[i..end].chars().filter(|&ch| ch == '\n'));
            i = end;
        } else if c == b'\'' && char_literal_len(b, i).is_some() {
            code.push_str("' '");
            i += char_literal_len(b, i).unwrap_or(1);
        } else {
            let ch = text[i..].chars().next().unwrap_or(' ');
            if ch == '\n' {
                comments.push('\n');
            }
            code.push(ch);
            i += ch.len_utf8();
        }
    }
    Split { code, comments }
}

/// The number of `#` of a raw string starting at `i` (`r"`, `r#"`), if one starts there.
fn raw_string_start(b: &[u8], i: usize) -> Option<usize> {
    if i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_') {
        return None;
    }
    let hashes = b[i + 1..].iter().take_while(|&&c| c == b'#').count();
    (b.get(i + 1 + hashes) == Some(&b'"')).then_some(hashes)
}

/// The index just past the string literal starting at `i` (plain or raw).
fn string_end(b: &[u8], i: usize) -> usize {
    if b[i] == b'r' {
        let hashes = raw_string_start(b, i).unwrap_or(0);
        let close: Vec<u8> =
            std::iter::once(b'"').chain(std::iter::repeat_n(b'#', hashes)).collect();
        let body = i + 2 + hashes;
        return b[body..]
            .windows(close.len())
            .position(|w| w == close)
            .map_or(b.len(), |p| body + p + close.len());
    }
    let mut j = i + 1;
    while j < b.len() {
        match b[j] {
            b'\\' => j += 2,
            b'"' => return j + 1,
            _ => j += 1,
        }
    }
    b.len()
}

/// The length of a char literal at `i` (`'a'`, `'\n'`, `'\u{..}'`), or None for a lifetime.
fn char_literal_len(b: &[u8], i: usize) -> Option<usize> {
    if b.get(i + 1) == Some(&b'\\') {
        let close = b[i + 2..].iter().position(|&c| c == b'\'')?;
        return Some(close + 3);
    }
    let rest = std::str::from_utf8(&b[i + 1..]).ok()?;
    let ch = rest.chars().next()?;
    (b.get(i + 1 + ch.len_utf8()) == Some(&b'\'')).then_some(ch.len_utf8() + 2)
}

/// The path relative to the repository root, with `/`, for messages.
pub fn shown(path: &Path) -> String {
    path.strip_prefix(root()).unwrap_or(path).to_string_lossy().replace('\\', "/")
}
