//! Resolving the paths a crate's files name to the files that define them, and the circles of
//! the resulting file graph (strongly connected components).

use super::imports::{Module, Modules, is_ident, use_trees};
use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;

/// File -> file it imports from -> the names it takes.
pub type Edges = BTreeMap<PathBuf, BTreeMap<PathBuf, BTreeSet<String>>>;

/// The crate's file graph from its modules' `use` declarations and inline paths.
pub fn file_edges(modules: &Modules) -> Edges {
    let mut edges = Edges::new();
    for (path, module) in modules {
        edges.entry(module.file.clone()).or_default();
        let used = module.uses.iter().filter(|(name, _)| !module.passed_on.contains(name));
        let mut named: Vec<Vec<String>> = used.map(|(_, path)| path.clone()).collect();
        named.extend(module.globs.iter().cloned());
        named.extend(inline_paths(&module.code));
        for segments in named {
            let Some(target) = resolve(modules, path, &segments, 0) else { continue };
            if target != module.file {
                let name = segments.last().cloned().unwrap_or_default();
                edges
                    .entry(module.file.clone())
                    .or_default()
                    .entry(target)
                    .or_default()
                    .insert(name);
            }
        }
    }
    edges
}

/// Paths written in the code outside `use` declarations that start at `crate::`, `super::` or
/// `self::` (not `$crate::`, a macro's own crate).
fn inline_paths(code: &str) -> Vec<Vec<String>> {
    let mut code = code.to_string();
    for tree in use_trees(&code) {
        code = code.replacen(&tree, "", 1);
    }
    let b = code.as_bytes();
    let mut out = Vec::new();
    for start in ["crate::", "super::", "self::"] {
        let mut from = 0;
        while let Some(at) = code[from..].find(start) {
            let i = from + at;
            from = i + start.len();
            if i > 0 && (is_ident(b[i - 1]) || b[i - 1] == b'$' || b[i - 1] == b':') {
                continue;
            }
            let mut end = i;
            while end < b.len() && (is_ident(b[end]) || code[end..].starts_with("::")) {
                end += if b[end] == b':' { 2 } else { 1 };
            }
            let text = code[i..end].trim_end_matches("::");
            out.push(text.split("::").map(str::to_string).collect());
        }
    }
    out
}

/// The file that defines what `segments` names, seen from module `from`; None for a path
/// outside the crate.
pub fn resolve(
    modules: &Modules,
    from: &[String],
    segments: &[String],
    depth: u32,
) -> Option<PathBuf> {
    let first = segments.first()?;
    let mut base: Vec<String> = from.to_vec();
    let mut rest = segments;
    match first.as_str() {
        "crate" => {
            base.clear();
            rest = &segments[1..];
        }
        "self" => rest = &segments[1..],
        "super" => {
            while rest.first().is_some_and(|s| s == "super") {
                base.pop();
                rest = &rest[1..];
            }
        }
        name if modules.get(from).is_some_and(|m| m.children.contains_key(name)) => {}
        _ => return None,
    }
    resolve_in(modules, &base, rest, depth)
}

fn resolve_in(modules: &Modules, at: &[String], rest: &[String], depth: u32) -> Option<PathBuf> {
    let module = modules.get(at)?;
    let Some(name) = rest.first() else { return Some(module.file.clone()) };
    if depth > 16 {
        return Some(module.file.clone());
    }
    if let Some(child) = module.children.get(name) {
        return resolve_in(modules, child, &rest[1..], depth + 1);
    }
    if defines(module, name) {
        return Some(module.file.clone());
    }
    if let Some(path) = module.uses.get(name) {
        // Through the import, on to the rest of the path (`gpu::grid_1d` where `gpu` is an
        // imported module). A name brought in from outside the crate is not a file of it.
        let full: Vec<String> = path.iter().chain(&rest[1..]).cloned().collect();
        return resolve(modules, at, &full, depth + 1);
    }
    for glob in &module.globs {
        let Some(target) = glob_module(modules, at, glob) else { continue };
        if let Some(m) = modules.get(&target)
            && (defines(m, name) || m.uses.contains_key(name) || m.children.contains_key(name))
        {
            return resolve_in(modules, &target, rest, depth + 1);
        }
    }
    Some(module.file.clone())
}

/// The module a glob import (`use path::*`) names, if it is one of the crate's.
fn glob_module(modules: &Modules, at: &[String], glob: &[String]) -> Option<Vec<String>> {
    let file = resolve(modules, at, glob, 0)?;
    modules.iter().find(|(_, m)| m.file == file).map(|(p, _)| p.clone())
}

/// Whether the module's own code defines an item called `name`.
fn defines(module: &Module, name: &str) -> bool {
    const KINDS: [&str; 10] =
        ["fn", "struct", "enum", "trait", "type", "const", "static", "union", "macro_rules", "mod"];
    let words: Vec<&str> = module
        .code
        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .filter(|w| !w.is_empty())
        .collect();
    words.windows(2).any(|w| w[1] == name && KINDS.contains(&w[0]))
}

/// The strongly connected components of more than one file (Tarjan's algorithm).
pub fn circles(edges: &Edges) -> Vec<Vec<PathBuf>> {
    let nodes: Vec<&PathBuf> = edges.keys().collect();
    let index_of: BTreeMap<&PathBuf, usize> =
        nodes.iter().enumerate().map(|(i, n)| (*n, i)).collect();
    let next: Vec<Vec<usize>> = nodes
        .iter()
        .map(|n| edges[*n].keys().filter_map(|t| index_of.get(t).copied()).collect())
        .collect();
    let mut t = Tarjan {
        next: &next,
        index: vec![None; nodes.len()],
        low: vec![0; nodes.len()],
        ..Tarjan::default()
    };
    for v in 0..nodes.len() {
        if t.index[v].is_none() {
            t.visit(v);
        }
    }
    t.components
        .into_iter()
        .filter(|c| c.len() > 1)
        .map(|c| c.into_iter().map(|i| nodes[i].clone()).collect())
        .collect()
}

#[derive(Default)]
struct Tarjan<'a> {
    next: &'a [Vec<usize>],
    index: Vec<Option<usize>>,
    low: Vec<usize>,
    stack: Vec<usize>,
    on_stack: BTreeSet<usize>,
    counter: usize,
    components: Vec<Vec<usize>>,
}

impl Tarjan<'_> {
    fn visit(&mut self, v: usize) {
        self.index[v] = Some(self.counter);
        self.low[v] = self.counter;
        self.counter += 1;
        self.stack.push(v);
        self.on_stack.insert(v);
        for &w in &self.next[v] {
            match self.index[w] {
                None => {
                    self.visit(w);
                    self.low[v] = self.low[v].min(self.low[w]);
                }
                Some(iw) if self.on_stack.contains(&w) => self.low[v] = self.low[v].min(iw),
                Some(_) => {}
            }
        }
        if Some(self.low[v]) == self.index[v] {
            let mut component = Vec::new();
            while let Some(w) = self.stack.pop() {
                self.on_stack.remove(&w);
                component.push(w);
                if w == v {
                    break;
                }
            }
            component.sort_unstable();
            self.components.push(component);
        }
    }
}
