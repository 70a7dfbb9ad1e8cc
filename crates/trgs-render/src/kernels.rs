//! Every compute pipeline of the renderer, compiled once per [`crate::Renderer`].
use crate::GpuContext;
use crate::gpu::Kernel;

#[derive(Debug)]
pub struct Kernels {
    pub project_candidates: Kernel,
    pub project: Kernel,
    pub tile_counts: Kernel,
    pub depth_order_compact: Kernel,
    pub depth_order_counts: Kernel,
    pub prefix_sum: Kernel,
    /// `prefix_sum`'s level scan of the set bits of each word (COUNT_BITS).
    pub prefix_sum_bits: Kernel,
    pub prefix_sum_add: Kernel,
    pub emit_keys: Kernel,
    pub sort_count: Kernel,
    pub sort_scatter: Kernel,
    pub tile_ranges: Kernel,
    pub rasterize: Kernel,
    pub rasterize_depth_variance: Kernel,
    pub rasterize_reflection: Kernel,
    pub compose: Kernel,
    pub compose_bwd: Kernel,
    pub display: Kernel,
    pub rasterize_bwd: Kernel,
    pub rasterize_reflection_bwd: Kernel,
    pub project_bwd: Kernel,
    /// `project_bwd` of a mirrored view: adds to the Gaussians' gradients (BWD_ADD).
    pub project_bwd_add: Kernel,
}

/// Defines of the accumulating (adjoint) kernels for the device's features: float atomics or the
/// compare-exchange fallback, with or without a subgroup reduction first.
pub fn accumulation_defines(caps: &crate::Capabilities) -> Vec<&'static str> {
    let mut d = Vec::new();
    if caps.float_atomics {
        d.push("FLOAT_ATOMICS");
    }
    if caps.subgroups {
        d.push("SUBGROUPS");
    }
    d
}

/// The define of the layout of `rasterize_reflection`, `rasterize_bwd` and
/// `rasterize_reflection_bwd` (none for one pixel per thread); why and what it measured:
/// `shaders/shared/tile_rows.wgsl` and docs/gpu-renderer.md, "Pixels per thread".
pub fn tile_defines(caps: &crate::Capabilities) -> &'static [&'static str] {
    match caps.tile_layout {
        crate::TileLayout::PixelPerThread => &[],
        crate::TileLayout::FourRowsPerThread => &["ROWS_PER_THREAD_4"],
    }
}

/// The define of the scan and sort block width (none for [`crate::BlockWidth::Narrow`]); why:
/// [`crate::BlockWidth`].
pub fn block_defines(caps: &crate::Capabilities) -> &'static [&'static str] {
    match caps.block_width {
        crate::BlockWidth::Narrow => &[],
        crate::BlockWidth::Wide => &["WIDE_BLOCKS"],
    }
}

impl Kernels {
    pub fn new(ctx: &GpuContext) -> Self {
        let acc = accumulation_defines(&ctx.capabilities);
        let tiles = tile_defines(&ctx.capabilities);
        let replay = [acc.as_slice(), tiles].concat();
        let blocks = block_defines(&ctx.capabilities);
        let walk: &[&str] = if ctx.capabilities.block_walk { &["BLOCK_WALK"] } else { &[] };
        Self {
            project_candidates: Kernel::new(
                ctx,
                "project_candidates",
                "project_candidates.wgsl",
                &[],
            ),
            project: Kernel::new(ctx, "project", "project.wgsl", &[]),
            tile_counts: Kernel::new(ctx, "tile_counts", "tile_counts.wgsl", &[]),
            depth_order_compact: Kernel::new(
                ctx,
                "depth_order_compact",
                "depth_order_compact.wgsl",
                &[],
            ),
            depth_order_counts: Kernel::new(
                ctx,
                "depth_order_counts",
                "depth_order_counts.wgsl",
                &[],
            ),
            prefix_sum: Kernel::new(ctx, "prefix_sum", "prefix_sum.wgsl", blocks),
            prefix_sum_bits: Kernel::new(
                ctx,
                "prefix_sum_bits",
                "prefix_sum.wgsl",
                &[blocks, &["COUNT_BITS"]].concat(),
            ),
            prefix_sum_add: Kernel::new(ctx, "prefix_sum_add", "prefix_sum_add.wgsl", blocks),
            emit_keys: Kernel::new(ctx, "emit_keys", "emit_keys.wgsl", &[]),
            sort_count: Kernel::new(ctx, "sort_count", "sort_count.wgsl", blocks),
            sort_scatter: Kernel::new(ctx, "sort_scatter", "sort_scatter.wgsl", blocks),
            tile_ranges: Kernel::new(ctx, "tile_ranges", "tile_ranges.wgsl", &[]),
            rasterize: Kernel::new(ctx, "rasterize", "rasterize.wgsl", walk),
            rasterize_depth_variance: Kernel::new(
                ctx,
                "rasterize",
                "rasterize.wgsl",
                &[walk, &["DEPTH_VARIANCE"]].concat(),
            ),
            rasterize_reflection: Kernel::new(
                ctx,
                "rasterize_reflection",
                "rasterize_reflection.wgsl",
                &[tiles, walk].concat(),
            ),
            compose: Kernel::new(ctx, "compose", "compose.wgsl", &[]),
            compose_bwd: Kernel::new(ctx, "compose_bwd", "compose_bwd.wgsl", &acc),
            display: Kernel::new(ctx, "display", "display.wgsl", &[]),
            rasterize_bwd: Kernel::new(
                ctx,
                "rasterize_bwd",
                "rasterize_bwd.wgsl",
                &[replay.as_slice(), walk].concat(),
            ),
            rasterize_reflection_bwd: Kernel::new(
                ctx,
                "rasterize_reflection_bwd",
                "rasterize_reflection_bwd.wgsl",
                &[replay.as_slice(), walk].concat(),
            ),
            project_bwd: Kernel::new(ctx, "project_bwd", "project_bwd.wgsl", &acc),
            project_bwd_add: Kernel::new(
                ctx,
                "project_bwd_add",
                "project_bwd.wgsl",
                &[acc.as_slice(), &["ADD_GRADIENTS"]].concat(),
            ),
        }
    }
}
