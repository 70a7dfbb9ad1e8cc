//! The import graph of one crate, file to file: each `use` of `crate::`, `super::`, `self::` or
//! a child module, and each such path written inline, points at the file that defines the item
//! it names, following re-exports (`pub use`) to where the item is defined, so that importing a
//! name through a folder's mod.rs ties the importer to the defining file, not to the mod.rs.

use super::source::{CrateRoot, split};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One module of a crate: its file, its code, the child modules it declares and its `use`
/// declarations (name brought in -> the path it names, relative to this module).
#[derive(Debug)]
pub struct Module {
    pub file: PathBuf,
    pub code: String,
    pub children: BTreeMap<String, Vec<String>>,
    pub uses: BTreeMap<String, Vec<String>>,
    /// Names of `uses` that the module only passes on (`pub use`) and does not use itself.
    pub passed_on: Vec<String>,
    pub globs: Vec<Vec<String>>,
}

/// The modules of a crate by their path (`[]` the root, `["densify", "mcmc"]`, ...).
pub type Modules = BTreeMap<Vec<String>, Module>;

/// Read every module file reachable from `krate`'s root through `mod` declarations (inline
/// `mod x { ... }` blocks, tests among them, stay part of their file).
pub fn modules(krate: &CrateRoot) -> Modules {
    let mut out = Modules::new();
    let mut todo = vec![(Vec::<String>::new(), krate.root_file.clone())];
    while let Some((path, file)) = todo.pop() {
        let text = std::fs::read_to_string(&file).unwrap_or_default();
        let code = without_inline_modules(&split(&text).code);
        let dir = child_dir(&file);
        let mut children = BTreeMap::new();
        for name in declared_modules(&code) {
            let (a, b) = (dir.join(format!("{name}.rs")), dir.join(&name).join("mod.rs"));
            let child = if a.is_file() { a } else { b };
            if child.is_file() {
                let mut child_path = path.clone();
                child_path.push(name.clone());
                children.insert(name, child_path.clone());
                todo.push((child_path, child));
            }
        }
        let (uses, globs) = use_declarations(&code);
        let passed_on = passed_on(&code);
        out.insert(path, Module { file, code, children, uses, passed_on, globs });
    }
    out
}

/// The code less its inline `mod name { ... }` blocks (the tests): what they import is theirs,
/// and their `super::` is the file's own module.
fn without_inline_modules(code: &str) -> String {
    let mut out = String::with_capacity(code.len());
    let mut rest = code;
    while let Some(at) = find_inline_module(rest) {
        out.push_str(&rest[..at]);
        let open = at + rest[at..].find('{').unwrap_or(0);
        let mut depth = 0;
        let mut end = rest.len();
        for (i, c) in rest[open..].char_indices() {
            match c {
                '{' => depth += 1,
                '}' => depth -= 1,
                _ => continue,
            }
            if depth == 0 {
                end = open + i + 1;
                break;
            }
        }
        out.extend(rest[at..end].chars().filter(|&c| c == '\n'));
        rest = &rest[end..];
    }
    out.push_str(rest);
    out
}

/// Where the next `mod name {` starts.
fn find_inline_module(code: &str) -> Option<usize> {
    let b = code.as_bytes();
    let mut from = 0;
    while let Some(at) = code[from..].find("mod ") {
        let i = from + at;
        from = i + 4;
        if i > 0 && is_ident(b[i - 1]) {
            continue;
        }
        let after = code[from..].trim_start();
        let name_len = after.bytes().take_while(|&c| is_ident(c)).count();
        if name_len > 0 && after[name_len..].trim_start().starts_with('{') {
            return Some(i);
        }
    }
    None
}

/// The folder a file's child modules live in: its own for lib.rs, main.rs and mod.rs, a folder
/// of its stem otherwise.
fn child_dir(file: &Path) -> PathBuf {
    let parent = file.parent().unwrap_or(Path::new(".")).to_path_buf();
    let name = file.file_name().unwrap_or_default().to_string_lossy();
    if matches!(name.as_ref(), "lib.rs" | "main.rs" | "mod.rs") {
        parent
    } else {
        parent.join(file.file_stem().unwrap_or_default())
    }
}

/// Names of `mod x;` declarations (files, not inline blocks).
fn declared_modules(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    for line in code.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        let Some(at) = words.iter().position(|&w| w == "mod") else { continue };
        let leading_ok = words[..at].iter().all(|w| w.starts_with("pub"));
        if let Some(name) = words.get(at + 1).and_then(|w| w.strip_suffix(';'))
            && leading_ok
        {
            out.push(name.to_string());
        }
    }
    out
}

/// Every `use` declaration's leaves: the name each brings into scope and the path it names
/// (`use a::{b::C, d as e}` -> C: a::b::C, e: a::d); globs apart.
fn use_declarations(code: &str) -> (BTreeMap<String, Vec<String>>, Vec<Vec<String>>) {
    let (mut named, mut globs) = (BTreeMap::new(), Vec::new());
    for tree in use_trees(code) {
        let (n, g) = use_declarations_of(&tree);
        named.extend(n);
        globs.extend(g);
    }
    (named, globs)
}

/// The leaves of one use tree, as [`use_declarations`].
fn use_declarations_of(tree: &str) -> (BTreeMap<String, Vec<String>>, Vec<Vec<String>>) {
    let (mut named, mut globs) = (BTreeMap::new(), Vec::new());
    {
        for leaf in expand(tree) {
            let (path, alias) = match leaf.split_once(" as ") {
                Some((p, a)) => (p.trim().to_string(), Some(a.trim().to_string())),
                None => (leaf.trim().to_string(), None),
            };
            let segments: Vec<String> = path.split("::").map(|s| s.trim().to_string()).collect();
            if segments.last().is_some_and(|s| s == "*") {
                globs.push(segments[..segments.len() - 1].to_vec());
            } else if let Some(last) = segments.last() {
                let name = alias.unwrap_or_else(|| last.clone());
                let segments =
                    if last == "self" { segments[..segments.len() - 1].to_vec() } else { segments };
                named.insert(name, segments);
            }
        }
    }
    (named, globs)
}

/// The names that `pub use` declarations re-export and the rest of the code does not mention:
/// a facade passes them on and depends on nothing of theirs.
fn passed_on(code: &str) -> Vec<String> {
    let mut rest = code.to_string();
    let mut exported = Vec::new();
    for tree in use_trees(code) {
        let at = rest.find(&tree).unwrap_or(0);
        let before = rest[..at].trim_end().trim_end_matches("use").trim_end();
        if before.ends_with("pub") || before.ends_with(')') {
            let (named, _) = use_declarations_of(&tree);
            exported.extend(named.into_keys());
        }
        rest = rest.replacen(&tree, "", 1);
    }
    let words: std::collections::BTreeSet<&str> =
        rest.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).collect();
    exported.into_iter().filter(|name| !words.contains(name.as_str())).collect()
}

/// The text of each `use ...;` declaration after `use`, white space folded.
pub fn use_trees(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let bytes = code.as_bytes();
    let mut from = 0;
    while let Some(at) = code[from..].find("use ") {
        let start = from + at;
        from = start + 4;
        let before_ok = start == 0 || !is_ident(bytes[start - 1]);
        if !before_ok {
            continue;
        }
        let Some(end) = code[from..].find(';') else { break };
        let tree: String = code[from..from + end].split_whitespace().collect::<Vec<_>>().join(" ");
        out.push(tree);
        from += end;
    }
    out
}

pub fn is_ident(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

/// `a::{b::{C, D}, e}` -> [a::b::C, a::b::D, a::e].
fn expand(tree: &str) -> Vec<String> {
    let tree = tree.trim();
    let Some(open) = tree.find('{') else { return vec![tree.to_string()] };
    let prefix = tree[..open].trim();
    let inner = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
    let mut parts = Vec::new();
    let (mut depth, mut start) = (0, 0);
    for (i, c) in inner.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&inner[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&inner[start..]);
    parts
        .into_iter()
        .filter(|p| !p.trim().is_empty())
        .flat_map(expand)
        .map(|leaf| format!("{prefix}{leaf}"))
        .collect()
}
