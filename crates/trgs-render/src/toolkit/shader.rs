//! WGSL sources: one file per stage under `shaders/` (single entry point `main`) in a folder by
//! where it runs (`render/`, `backward/`, `training/`, `bench/`), shared helpers under
//! `shaders/shared/`, combined by a small preprocessor: `#include "shared/<name>.wgsl"` (each file
//! once), and `#ifdef NAME` / `#ifndef NAME` / `#else` / `#endif` against the variant's defines.
//! Every shader starts with a prelude of constants and struct declarations generated from Rust
//! ([`super::layout::prelude`], and a crate's own structs after it).
//! The build script compiles every file under `shaders/` in ([`SOURCES`]).
use std::collections::HashSet;

include!(concat!(env!("OUT_DIR"), "/shader_sources.rs"));

#[derive(Debug, thiserror::Error)]
pub enum ShaderError {
    #[error("shaders/{0}: no such WGSL file")]
    Missing(String),
    #[error("shaders/{file}:{line}: {problem}")]
    Syntax { file: String, line: usize, problem: String },
}

fn source(name: &str) -> Result<&'static str, ShaderError> {
    SOURCES
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, s)| *s)
        .ok_or_else(|| ShaderError::Missing(name.to_string()))
}

/// The complete WGSL of `name` with `defines`: the renderer's prelude, includes expanded,
/// conditionals resolved.
pub fn compose(name: &str, defines: &[&str]) -> Result<String, ShaderError> {
    compose_after(crate::layout::prelude(), name, defines)
}

/// [`compose`] after another `prelude` (a crate's own, which extends the renderer's).
pub fn compose_after(prelude: String, name: &str, defines: &[&str]) -> Result<String, ShaderError> {
    let mut out = prelude;
    let mut included = HashSet::new();
    expand(name, defines, &mut included, &mut out)?;
    Ok(out)
}

fn expand(
    name: &str,
    defines: &[&str],
    included: &mut HashSet<String>,
    out: &mut String,
) -> Result<(), ShaderError> {
    if !included.insert(name.to_string()) {
        return Ok(());
    }
    let text = source(name)?;
    // Stack of (this branch active, some branch of this #if was taken).
    let mut stack: Vec<(bool, bool)> = Vec::new();
    let err = |line: usize, problem: &str| ShaderError::Syntax {
        file: name.to_string(),
        line: line + 1,
        problem: problem.to_string(),
    };
    for (ln, line) in text.lines().enumerate() {
        let t = line.trim();
        let active = stack.iter().all(|&(a, _)| a);
        if let Some(rest) = t.strip_prefix("#ifdef ").or_else(|| t.strip_prefix("#ifndef ")) {
            let want = t.starts_with("#ifdef ");
            let on = defines.contains(&rest.trim()) == want;
            stack.push((on, on));
        } else if t == "#else" {
            let top = stack.last_mut().ok_or_else(|| err(ln, "#else without #ifdef"))?;
            *top = (!top.1, true);
        } else if t == "#endif" {
            stack.pop().ok_or_else(|| err(ln, "#endif without #ifdef"))?;
        } else if let Some(rest) = t.strip_prefix("#include ") {
            if active {
                let inc = rest.trim().trim_matches('"');
                expand(inc, defines, included, out)?;
            }
        } else if t.starts_with('#') {
            return Err(err(ln, "unknown directive"));
        } else if active {
            out.push_str(line);
            out.push('\n');
        }
    }
    if !stack.is_empty() {
        return Err(err(text.lines().count(), "#ifdef without #endif"));
    }
    Ok(())
}
