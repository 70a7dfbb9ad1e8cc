//! Stage `gather_rows` on the GPU (shaders/training/gather_rows.wgsl; twin [`RowPlan::apply`]):
//! rebuild the Gaussians' attribute and Adam-moment buffers from a [`RowPlan`] without reading
//! them back: the sources come from the deciding stages on the GPU (`densify_plan`,
//! `mcmc_relocate`) or from a plan made on the CPU. The parameters with their two moments are
//! about 180 words per Gaussian at SH degree 3, and reading the whole state back, editing it on
//! the CPU and uploading it again costs many steps' time (`bench --densify` measures the ways).
use super::adam::AdamMoments;
use super::plan::RowPlan;
use crate::layout::{GATHER_ZERO, GatherParams};
use trgs_core::scene::{Attribute, PerAttribute};
use trgs_render::toolkit::gpu::{self, Kernel, Recorder, grid_1d, range};
use trgs_render::{GpuContext, GpuScene};

/// The kernel and the binding limit it works under.
#[derive(Debug)]
pub struct GpuRowGather {
    kernel: Kernel,
    /// Words per binding range.
    binding_words: u64,
}

/// What a gather pass writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum GatherMode {
    /// Every row, a copy of its source (parameters).
    Copy,
    /// Every row; those made anew (GATHER_ZERO) are zero (Adam moments that restart).
    ZeroAnew,
    /// Only the rows made anew, each from the same row of the source buffer: a plan's given
    /// values, over a buffer gathered before.
    GivenAnew,
}

/// A plan's output rows as GPU source indices (GATHER_ZERO marks rows whose moments restart).
#[derive(Debug)]
pub struct GatherSources {
    buffer: wgpu::Buffer,
    len: u32,
}

impl GatherSources {
    pub fn new(ctx: &GpuContext, sources: &[(usize, bool)]) -> Self {
        let words: Vec<u32> = sources
            .iter()
            .map(|&(i, keep)| {
                debug_assert!((i as u64) < u64::from(GATHER_ZERO), "row index {i} out of range");
                i as u32 | if keep { 0 } else { GATHER_ZERO }
            })
            .collect();
        Self {
            buffer: gpu::storage_init(ctx, "trgs.gather_rows.sources", &words),
            len: words.len() as u32,
        }
    }

    /// Sources made on the GPU (`densify_plan`, `mcmc_relocate`): the first `len` words of
    /// `buffer`.
    pub fn from_buffer(buffer: wgpu::Buffer, len: u32) -> Self {
        debug_assert!(u64::from(len) * 4 <= buffer.size(), "{len} sources in a shorter buffer");
        Self { buffer, len }
    }

    pub fn len(&self) -> u32 {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

impl GpuRowGather {
    pub fn new(ctx: &GpuContext) -> Self {
        let limit = ctx.binding_limit();
        Self {
            kernel: crate::kernels::TRAINING_KERNELS.gather_rows.build(ctx),
            binding_words: (limit / 4).min(1 << 30),
        }
    }

    /// Bind ranges of at most `words` words, or of 64 rows where a row is wider than a 64th of
    /// that (tests exercise the ranges that large buffers need).
    pub fn set_binding_words(&mut self, words: u64) {
        self.binding_words = self.binding_words.min(words.max(64));
    }

    /// Rows of `width` words per binding range: a multiple of 64, so that every range offset is
    /// a multiple of 256 bytes.
    fn rows_per_range(&self, width: u32) -> u32 {
        let rows = self.binding_words / u64::from(width.max(1));
        (rows / 64 * 64).clamp(64, u64::from(u32::MAX / 2)) as u32
    }

    /// Record the gather of `src` (`src_rows` rows of `width` words) into a new buffer of
    /// `sources.len()` rows, by `mode` (zero rows only with [`GatherMode::ZeroAnew`]).
    #[allow(clippy::too_many_arguments)]
    fn record(
        &self,
        ctx: &GpuContext,
        rec: &mut Recorder,
        label: &str,
        src: &wgpu::Buffer,
        src_rows: u32,
        width: u32,
        sources: &GatherSources,
        mode: GatherMode,
    ) -> wgpu::Buffer {
        let dst = gpu::storage(ctx, label, u64::from(sources.len) * u64::from(width) * 4);
        self.record_into(ctx, rec, &dst, src, src_rows, width, sources, mode);
        dst
    }

    /// Record a gather pass of `src` into `dst` (`sources.len()` rows of `width` words).
    #[allow(clippy::too_many_arguments)]
    fn record_into(
        &self,
        ctx: &GpuContext,
        rec: &mut Recorder,
        dst: &wgpu::Buffer,
        src: &wgpu::Buffer,
        src_rows: u32,
        width: u32,
        sources: &GatherSources,
        mode: GatherMode,
    ) {
        let (n, w) = (sources.len, u64::from(width));
        let per_range = self.rows_per_range(width);
        let starts = |rows: u32| (0..rows.div_ceil(per_range)).map(move |r| r * per_range);
        for first in starts(n) {
            let count = per_range.min(n - first);
            for first_source in starts(src_rows.max(1)) {
                let source_rows = per_range.min(src_rows.saturating_sub(first_source));
                let params = GatherParams {
                    count,
                    width,
                    first_source,
                    source_rows,
                    honour_zero: u32::from(mode == GatherMode::ZeroAnew),
                    given_rows: u32::from(mode == GatherMode::GivenAnew),
                    first_row: first,
                    ..Default::default()
                };
                let block = gpu::params(ctx, "trgs.gather_rows.params", &params);
                let (f, s) = (u64::from(first), u64::from(first_source));
                // An empty source range still binds a valid (minimal) range.
                let src_words = (u64::from(source_rows) * w).max(1);
                let bind = self.kernel.bind(
                    ctx,
                    &[
                        block.as_entire_binding(),
                        range(&sources.buffer, f * 4, u64::from(count) * 4),
                        range(src, s * w * 4, src_words * 4),
                        range(dst, f * w * 4, u64::from(count) * w * 4),
                    ],
                );
                let groups = count.div_ceil(256);
                rec.dispatch("gather_rows", &self.kernel, &bind, grid_1d(groups));
            }
        }
    }

    /// The scene and moments that `plan` makes of `scene` and `moments`, gathered on the GPU;
    /// the attributes the plan gives whole are written as given.
    pub fn apply(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        moments: &PerAttribute<AdamMoments>,
        plan: &RowPlan,
    ) -> Result<(GpuScene, PerAttribute<AdamMoments>), gpu::GpuError> {
        let sources = GatherSources::new(ctx, &plan.sources);
        let given: Vec<(Attribute, wgpu::Buffer)> = plan
            .given_words()
            .into_iter()
            .map(|(a, words)| {
                (a, gpu::storage_init(ctx, &format!("trgs.scene.{}", a.name()), &words))
            })
            .collect();
        self.apply_sources(ctx, scene, moments, &sources, &given, |_, _| {})
    }

    /// The scene and moments gathered by `sources`, with the attributes in `given` (buffers of
    /// the new set's size) giving the rows made anew (GATHER_ZERO) their values: a kept row is
    /// its source as it is now, which may have trained a step since the plan was decided (see
    /// [`RowPlan::apply`]); `then` records what edits the new scene before the one submission
    /// (the split children's means and scales of `densify_plan`).
    pub fn apply_sources(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        moments: &PerAttribute<AdamMoments>,
        sources: &GatherSources,
        given: &[(Attribute, wgpu::Buffer)],
        then: impl FnOnce(&mut Recorder, &GpuScene),
    ) -> Result<(GpuScene, PerAttribute<AdamMoments>), gpu::GpuError> {
        let scopes = gpu::ErrorScopes::open(ctx, "rebuilding the Gaussians");
        let n_src = scene.len();
        let mut rec = Recorder::new(ctx, "trgs.gather_rows", false);
        let rebuilt = scene.rebuilt(sources.len(), |buffer, width, label| {
            let copy = GatherMode::Copy;
            let dst = self.record(ctx, &mut rec, label, buffer, n_src, width, sources, copy);
            let given = given.iter().find(|(a, _)| label == format!("trgs.scene.{}", a.name()));
            if let Some((_, values)) = given {
                let (rows, mode) = (sources.len, GatherMode::GivenAnew);
                self.record_into(ctx, &mut rec, &dst, values, rows, width, sources, mode);
            }
            dst
        });
        let widths = scene.attribute_widths();
        let moments = PerAttribute::from_fn(|a| {
            let (mo, width) = (&moments[a], widths[a]);
            let mut gather = |b: &wgpu::Buffer, which: &str| {
                let label = format!("trgs.adam.{}.{which}", a.name());
                self.record(ctx, &mut rec, &label, b, n_src, width, sources, GatherMode::ZeroAnew)
            };
            let (m, v) = (gather(&mo.m, "m"), gather(&mo.v, "v"));
            AdamMoments { m, v, len: u64::from(sources.len()) * u64::from(width) }
        });
        then(&mut rec, &rebuilt);
        // Not waited for: the next step queues behind it, and the old set's buffers live on
        // (in wgpu) until the gather that reads them is done.
        let submitted = rec.submit(ctx);
        scopes.close_after(submitted.map(|_| (rebuilt, moments)))
    }
}
