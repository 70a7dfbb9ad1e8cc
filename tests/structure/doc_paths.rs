//! The paths that the docs and the code's comments name: README.md, docs/*.md and every comment
//! of every `.rs` and `.wgsl` file. A path names a file of the repository when it starts at one
//! of its top folders (`crates/`, `shaders/`, `docs/` ...) or is a source file of the project's
//! kinds (`.rs`, `.wgsl`, `.md`); such a path must exist, from the folder of the file that names
//! it or as the end of some file's path (`stages/sort.rs`). Other files named without a top
//! folder (`metrics.py`) are taken to be other projects', as is a path after `$` (an environment
//! variable's folder). `{a,b}` lists and `*` globs are expanded; a path with a placeholder
//! (`<stem>`) is a run's output, not a file of the repository.

use super::source::{files_with, root, shown, split};
use std::path::{Path, PathBuf};

/// Top folders a repository path can start at.
const TOP: [&str; 9] =
    ["crates/", "apps/", "shaders/", "docs/", "scripts/", "tests/", "src/", ".ci/", "target/"];
/// Endings of the project's source files named on their own.
const SOURCE: [&str; 3] = [".rs", ".wgsl", ".md"];

/// Every file of the repository (relative, with `/`), for suffix and glob matching.
pub fn repository_files() -> Vec<String> {
    files_with(&root(), "").iter().map(|p| shown(p)).collect()
}

/// The texts to check: (file, the text in which paths are named).
pub fn documents() -> Vec<(PathBuf, String)> {
    let root = root();
    let mut out = Vec::new();
    let mut markdown = vec![root.join("README.md")];
    markdown.extend(files_with(&root.join("docs"), ".md"));
    for path in markdown {
        out.push((path.clone(), std::fs::read_to_string(&path).unwrap_or_default()));
    }
    // WGSL's comments are written as Rust's, so the same split finds them.
    let mut sources = files_with(&root, ".rs");
    sources.extend(files_with(&root.join("shaders"), ".wgsl"));
    for path in sources {
        let text = std::fs::read_to_string(&path).unwrap_or_default();
        out.push((path, split(&text).comments));
    }
    out
}

/// The path-like words of a text: runs of path characters with a `/` or a source ending.
pub fn named_paths(text: &str) -> Vec<String> {
    let is_path_char = |c: char| c.is_ascii_alphanumeric() || "_-./{},*<>".contains(c);
    let mut out = Vec::new();
    for word in text.split(|c: char| !is_path_char(c)) {
        // Where the word starts in `text` (it is a slice of it).
        let start = word.as_ptr() as usize - text.as_ptr() as usize;
        if text[..start].ends_with('$') {
            continue;
        }
        let word = word.trim_start_matches(['.', ',']).trim_end_matches(['.', ',']);
        let word = word.trim_start_matches("./");
        let starts_at_top = TOP.iter().any(|t| word.starts_with(t));
        let is_source = SOURCE.iter().any(|e| word.ends_with(e)) && !word.starts_with('.');
        if (starts_at_top || is_source) && !word.contains('<') && !word.contains("//") {
            out.push(word.to_string());
        }
    }
    out
}

/// `sort_{count,scatter}.wgsl` -> [`sort_count.wgsl`, `sort_scatter.wgsl`].
fn expand_braces(path: &str) -> Vec<String> {
    let (Some(open), Some(close)) = (path.find('{'), path.find('}')) else {
        return vec![path.to_string()];
    };
    if close < open {
        return vec![path.to_string()];
    }
    path[open + 1..close]
        .split(',')
        .flat_map(|alt| expand_braces(&format!("{}{alt}{}", &path[..open], &path[close + 1..])))
        .collect()
}

/// Whether `pattern` (`*` any run of characters within a name) matches `name`.
fn glob_matches(pattern: &str, name: &str) -> bool {
    match pattern.split_once('*') {
        None => pattern == name,
        Some((head, tail)) => {
            name.starts_with(head)
                && (head.len()..=name.len())
                    .any(|i| glob_matches(tail, &name[i..]) && !name[head.len()..i].contains('/'))
        }
    }
}

/// Whether the path named in `doc` exists (see the module docs for where it is looked for).
pub fn exists(named: &str, doc: &Path, files: &[String]) -> bool {
    if named.starts_with("target/") {
        return true;
    }
    let doc_dir = shown(doc.parent().unwrap_or(Path::new("")));
    expand_braces(named).iter().all(|path| {
        let last = path.trim_end_matches('/').rsplit('/').next().unwrap_or("");
        let folder = path.ends_with('/') || !last.contains('.');
        let path = normalise(path);
        let relative = normalise(&format!("{doc_dir}/{path}"));
        files.iter().any(|f| names(&relative, f, folder) || suffix_names(&path, f, folder))
    })
}

/// Whether `pattern` names the file `f`, or with `folder` one of the folders above it.
fn names(pattern: &str, f: &str, folder: bool) -> bool {
    glob_matches(pattern, f)
        || (folder && f.match_indices('/').any(|(i, _)| glob_matches(pattern, &f[..i])))
}

/// Whether `pattern` names the end of `f`'s path (`stages/sort.rs`, `sort_count.wgsl`).
fn suffix_names(pattern: &str, f: &str, folder: bool) -> bool {
    std::iter::once(0)
        .chain(f.match_indices('/').map(|(i, _)| i + 1))
        .any(|start| names(pattern, &f[start..], folder))
}

/// Folds `a/./b` and `a/x/../b`.
fn normalise(path: &str) -> String {
    let mut parts: Vec<&str> = Vec::new();
    for part in path.split('/') {
        match part {
            "" | "." => {}
            ".." => {
                parts.pop();
            }
            p => parts.push(p),
        }
    }
    parts.join("/")
}
