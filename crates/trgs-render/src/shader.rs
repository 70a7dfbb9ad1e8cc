//! WGSL sources: one file per stage under `shaders/` (single entry point `main`), shared helpers
//! under `shaders/shared/`, combined by a small preprocessor: `#include "shared/x.wgsl"` (each file
//! once), and `#ifdef NAME` / `#ifndef NAME` / `#else` / `#endif` against the variant's defines.
//! Every shader starts with [`crate::layout::prelude`].
use std::collections::HashSet;

macro_rules! sources {
    ($($name:literal),* $(,)?) => {
        &[$(($name, include_str!(concat!("../../../shaders/", $name)))),*]
    };
}

/// Every WGSL file, by its path under `shaders/`.
pub const SOURCES: &[(&str, &str)] = sources!(
    "shared/common.wgsl",
    "shared/tiles.wgsl",
    "shared/tile_rows.wgsl",
    "shared/splat.wgsl",
    "shared/block_walk.wgsl",
    "shared/block_width.wgsl",
    "shared/sort_digit.wgsl",
    "shared/plane_hit.wgsl",
    "shared/accumulate.wgsl",
    "shared/sh.wgsl",
    "shared/random.wgsl",
    "shared/project_cull.wgsl",
    "project_candidates.wgsl",
    "project.wgsl",
    "tile_counts.wgsl",
    "depth_order_compact.wgsl",
    "depth_order_counts.wgsl",
    "prefix_sum.wgsl",
    "prefix_sum_add.wgsl",
    "emit_keys.wgsl",
    "sort_count.wgsl",
    "sort_scatter.wgsl",
    "tile_ranges.wgsl",
    "rasterize.wgsl",
    "rasterize_reflection.wgsl",
    "compose.wgsl",
    "display.wgsl",
    "compose_bwd.wgsl",
    "rasterize_bwd.wgsl",
    "rasterize_reflection_bwd.wgsl",
    "project_bwd.wgsl",
    "splat_loop.wgsl",
    "spread_block_check.wgsl",
    "adam.wgsl",
    "mcmc_regularise.wgsl",
    "mcmc_noise.wgsl",
    "densify_stats.wgsl",
    "gather_rows.wgsl",
    "photometric_loss_rows.wgsl",
    "photometric_loss.wgsl",
    "photometric_loss_grad_rows.wgsl",
    "photometric_loss_grad.wgsl",
    "regularisers.wgsl",
    "loss_sums.wgsl",
);

/// Every (stage file, defines) combination the renderer compiles; a test validates each with naga.
pub const VARIANTS: &[(&str, &[&str])] = &[
    ("project_candidates.wgsl", &[]),
    ("project.wgsl", &[]),
    ("tile_counts.wgsl", &[]),
    ("depth_order_compact.wgsl", &[]),
    ("depth_order_counts.wgsl", &[]),
    ("prefix_sum.wgsl", &[]),
    ("prefix_sum.wgsl", &["WIDE_BLOCKS"]),
    ("prefix_sum.wgsl", &["COUNT_BITS"]),
    ("prefix_sum.wgsl", &["WIDE_BLOCKS", "COUNT_BITS"]),
    ("prefix_sum_add.wgsl", &[]),
    ("prefix_sum_add.wgsl", &["WIDE_BLOCKS"]),
    ("emit_keys.wgsl", &[]),
    ("sort_count.wgsl", &[]),
    ("sort_count.wgsl", &["WIDE_BLOCKS"]),
    ("sort_scatter.wgsl", &[]),
    ("sort_scatter.wgsl", &["WIDE_BLOCKS"]),
    ("tile_ranges.wgsl", &[]),
    ("rasterize.wgsl", &[]),
    ("rasterize.wgsl", &["DEPTH_VARIANCE"]),
    ("rasterize.wgsl", &["BLOCK_WALK"]),
    ("rasterize.wgsl", &["BLOCK_WALK", "DEPTH_VARIANCE"]),
    ("rasterize_reflection.wgsl", &[]),
    ("rasterize_reflection.wgsl", &["ROWS_PER_THREAD_4"]),
    ("rasterize_reflection.wgsl", &["BLOCK_WALK"]),
    ("rasterize_reflection.wgsl", &["ROWS_PER_THREAD_4", "BLOCK_WALK"]),
    ("compose.wgsl", &[]),
    ("display.wgsl", &[]),
    ("compose_bwd.wgsl", &[]),
    ("compose_bwd.wgsl", &["FLOAT_ATOMICS"]),
    ("compose_bwd.wgsl", &["SUBGROUPS"]),
    ("compose_bwd.wgsl", &["FLOAT_ATOMICS", "SUBGROUPS"]),
    ("rasterize_bwd.wgsl", &[]),
    ("rasterize_bwd.wgsl", &["FLOAT_ATOMICS"]),
    ("rasterize_bwd.wgsl", &["SUBGROUPS"]),
    ("rasterize_bwd.wgsl", &["FLOAT_ATOMICS", "SUBGROUPS"]),
    ("rasterize_bwd.wgsl", &["ROWS_PER_THREAD_4"]),
    ("rasterize_bwd.wgsl", &["FLOAT_ATOMICS", "SUBGROUPS", "ROWS_PER_THREAD_4"]),
    ("rasterize_bwd.wgsl", &["SUBGROUPS", "BLOCK_WALK"]),
    ("rasterize_bwd.wgsl", &["FLOAT_ATOMICS", "SUBGROUPS", "BLOCK_WALK"]),
    ("rasterize_bwd.wgsl", &["SUBGROUPS", "ROWS_PER_THREAD_4", "BLOCK_WALK"]),
    ("rasterize_bwd.wgsl", &["FLOAT_ATOMICS", "SUBGROUPS", "ROWS_PER_THREAD_4", "BLOCK_WALK"]),
    ("rasterize_reflection_bwd.wgsl", &[]),
    ("rasterize_reflection_bwd.wgsl", &["FLOAT_ATOMICS"]),
    ("rasterize_reflection_bwd.wgsl", &["SUBGROUPS"]),
    ("rasterize_reflection_bwd.wgsl", &["FLOAT_ATOMICS", "SUBGROUPS"]),
    ("rasterize_reflection_bwd.wgsl", &["ROWS_PER_THREAD_4"]),
    ("rasterize_reflection_bwd.wgsl", &["FLOAT_ATOMICS", "SUBGROUPS", "ROWS_PER_THREAD_4"]),
    ("rasterize_reflection_bwd.wgsl", &["SUBGROUPS", "BLOCK_WALK"]),
    ("rasterize_reflection_bwd.wgsl", &["FLOAT_ATOMICS", "SUBGROUPS", "BLOCK_WALK"]),
    ("rasterize_reflection_bwd.wgsl", &["SUBGROUPS", "ROWS_PER_THREAD_4", "BLOCK_WALK"]),
    (
        "rasterize_reflection_bwd.wgsl",
        &["FLOAT_ATOMICS", "SUBGROUPS", "ROWS_PER_THREAD_4", "BLOCK_WALK"],
    ),
    ("project_bwd.wgsl", &[]),
    ("project_bwd.wgsl", &["FLOAT_ATOMICS"]),
    ("project_bwd.wgsl", &["SUBGROUPS"]),
    ("project_bwd.wgsl", &["FLOAT_ATOMICS", "SUBGROUPS"]),
    ("project_bwd.wgsl", &["ADD_GRADIENTS"]),
    ("project_bwd.wgsl", &["FLOAT_ATOMICS", "ADD_GRADIENTS"]),
    ("project_bwd.wgsl", &["SUBGROUPS", "ADD_GRADIENTS"]),
    ("project_bwd.wgsl", &["FLOAT_ATOMICS", "SUBGROUPS", "ADD_GRADIENTS"]),
    ("splat_loop.wgsl", &[]),
    ("spread_block_check.wgsl", &[]),
    ("adam.wgsl", &[]),
    ("mcmc_regularise.wgsl", &[]),
    ("mcmc_noise.wgsl", &[]),
    ("densify_stats.wgsl", &[]),
    ("gather_rows.wgsl", &[]),
    ("photometric_loss_rows.wgsl", &[]),
    ("photometric_loss.wgsl", &[]),
    ("photometric_loss_grad_rows.wgsl", &[]),
    ("photometric_loss_grad.wgsl", &[]),
    ("regularisers.wgsl", &[]),
    ("loss_sums.wgsl", &[]),
];

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

/// The complete WGSL of `name` with `defines`: prelude, includes expanded, conditionals resolved.
pub fn compose(name: &str, defines: &[&str]) -> Result<String, ShaderError> {
    let mut out = crate::layout::prelude();
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
