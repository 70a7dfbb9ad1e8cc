//! The renderer's kernel tables: every compute pipeline of the renderer (compiled once per
//! [`crate::Renderer`]), and the kernels of benchmarks and tests.
use crate::toolkit::registry::{
    accumulation, adjoint_tile_rows, block_walk, block_width, no_defines, tile_rows,
};

crate::kernel_registry! {
    /// Every kernel of the renderer: the forward stages, then the adjoints.
    pub const RENDER_KERNELS: RenderKernelSpecs => Kernels, prelude: crate::layout::prelude, {
        project_candidates: "render/project_candidates.wgsl" => no_defines,
        project: "render/project.wgsl" => no_defines,
        tile_counts: "render/tile_counts.wgsl" => no_defines,
        depth_order_compact: "render/depth_order_compact.wgsl" => no_defines,
        depth_order_counts: "render/depth_order_counts.wgsl" => no_defines,
        prefix_sum: "render/prefix_sum.wgsl" => block_width,
        /// `prefix_sum`'s level scan of the set bits of each word.
        prefix_sum_bits: "render/prefix_sum.wgsl" =>
            |c| [block_width(c), vec!["COUNT_BITS"]].concat(),
        prefix_sum_add: "render/prefix_sum_add.wgsl" => block_width,
        emit_keys: "render/emit_keys.wgsl" => no_defines,
        sort_count: "render/sort_count.wgsl" => block_width,
        sort_scatter: "render/sort_scatter.wgsl" => block_width,
        tile_ranges: "render/tile_ranges.wgsl" => no_defines,
        /// The key-list kernels with `_paged` handle a list of two pages (`toolkit::paged`): the
        /// frame's tile keys beyond one binding.
        emit_keys_paged: "render/emit_keys.wgsl" => |_| vec!["PAGED"],
        sort_count_paged: "render/sort_count.wgsl" => |c| [block_width(c), vec!["PAGED"]].concat(),
        sort_scatter_paged: "render/sort_scatter.wgsl" =>
            |c| [block_width(c), vec!["PAGED"]].concat(),
        tile_ranges_paged: "render/tile_ranges.wgsl" => |_| vec!["PAGED"],
        rasterize: "render/rasterize.wgsl" => block_walk,
        /// `rasterize` with the depth-variance layer (for L_d).
        rasterize_depth_variance: "render/rasterize.wgsl" =>
            |c| [block_walk(c), vec!["DEPTH_VARIANCE"]].concat(),
        /// The rasterize kernels with `_paged` read a frame with a second page of projected
        /// Gaussians or of key values (`toolkit::paged`); the others, one page of each with
        /// nothing to choose.
        rasterize_paged: "render/rasterize.wgsl" => |c| [block_walk(c), vec!["PAGED"]].concat(),
        rasterize_depth_variance_paged: "render/rasterize.wgsl" =>
            |c| [block_walk(c), vec!["DEPTH_VARIANCE", "PAGED"]].concat(),
        rasterize_reflection: "render/rasterize_reflection.wgsl" =>
            |c| [tile_rows(c), block_walk(c)].concat(),
        rasterize_reflection_paged: "render/rasterize_reflection.wgsl" =>
            |c| [tile_rows(c), block_walk(c), vec!["PAGED"]].concat(),
        compose: "render/compose.wgsl" => no_defines,
        display: "render/display.wgsl" => no_defines,
        compose_bwd: "backward/compose_bwd.wgsl" => accumulation,
        rasterize_bwd: "backward/rasterize_bwd.wgsl" =>
            |c| [accumulation(c), adjoint_tile_rows(c), block_walk(c)].concat(),
        rasterize_bwd_paged: "backward/rasterize_bwd.wgsl" =>
            |c| [accumulation(c), adjoint_tile_rows(c), block_walk(c), vec!["PAGED"]].concat(),
        rasterize_reflection_bwd: "backward/rasterize_reflection_bwd.wgsl" =>
            |c| [accumulation(c), adjoint_tile_rows(c), block_walk(c)].concat(),
        rasterize_reflection_bwd_paged: "backward/rasterize_reflection_bwd.wgsl" =>
            |c| [accumulation(c), adjoint_tile_rows(c), block_walk(c), vec!["PAGED"]].concat(),
        project_bwd: "backward/project_bwd.wgsl" => accumulation,
        /// `project_bwd` of a mirrored view: adds to the Gaussians' gradients (BWD_ADD).
        project_bwd_add: "backward/project_bwd.wgsl" =>
            |c| [accumulation(c), vec!["ADD_GRADIENTS"]].concat(),
    }
}

crate::kernel_registry! {
    /// Kernels of benchmarks and tests, apart from rendering and training: the trivial tiled
    /// splat loop that `bench` measures `rasterize` against, the check of the workgroup spread
    /// of dispatches whose counts are known on the GPU only, and the check of the random draws'
    /// integer arithmetic.
    pub const BENCH_KERNELS: BenchKernelSpecs => BenchKernels, prelude: crate::layout::prelude, {
        splat_loop: "bench/splat_loop.wgsl" => no_defines,
        spread_block_check: "bench/spread_block_check.wgsl" => no_defines,
        draw_below_check: "bench/draw_below_check.wgsl" => no_defines,
    }
}
