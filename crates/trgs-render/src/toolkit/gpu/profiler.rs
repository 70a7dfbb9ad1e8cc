//! Timestamp queries around a recorder's passes, summed per kernel within each stage.
use super::{GpuError, map_and_read};
use crate::GpuContext;

/// GPU time of one kernel's dispatches within one stage, from timestamp queries.
#[derive(Clone, Debug, PartialEq)]
pub struct KernelTime {
    pub stage: &'static str,
    /// The kernel's name in `Kernels` (its WGSL file's stem, or the stem and the variant).
    pub kernel: &'static str,
    pub ms: f64,
    /// Timed dispatches: passes past the query set's capacity in one submission go untimed.
    pub dispatches: u32,
}

/// Queries per submission: (begin, end) of at most half as many passes.
const CAPACITY: u32 = 512;

/// Timestamp queries around every pass, resolved per submission.
#[derive(Debug)]
pub(super) struct Profiler {
    queries: wgpu::QuerySet,
    /// (Stage, kernel) of every pass timed in the current submission, in query order.
    pending: Vec<(&'static str, &'static str)>,
    /// Milliseconds per kernel within a stage, over the resolved submissions, in first-recorded
    /// order.
    pub(super) kernels: Vec<KernelTime>,
}

impl Profiler {
    pub(super) fn new(ctx: &GpuContext) -> Self {
        let queries = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("trgs.profiler.queries"),
            ty: wgpu::QueryType::Timestamp,
            count: CAPACITY,
        });
        Self { queries, pending: Vec::new(), kernels: Vec::new() }
    }

    /// The timestamp writes of the next pass, while the query set has room.
    pub(super) fn timestamp_writes(
        &mut self,
        stage: &'static str,
        kernel: &'static str,
    ) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let i = self.pending.len() as u32;
        if (i + 1) * 2 > CAPACITY {
            return None;
        }
        self.pending.push((stage, kernel));
        Some(wgpu::ComputePassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: Some(2 * i),
            end_of_pass_write_index: Some(2 * i + 1),
        })
    }

    /// Records the copy of this submission's timestamps into a buffer to map once the
    /// submission is done; None when no pass was timed.
    pub(super) fn record_resolve(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Option<wgpu::Buffer> {
        let n = self.pending.len() as u32 * 2;
        if n == 0 {
            return None;
        }
        let buffer = |label, usage| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: u64::from(n) * 8,
                usage,
                mapped_at_creation: false,
            })
        };
        let resolved = buffer(
            "trgs.profiler.resolved",
            wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
        );
        let staging = buffer(
            "trgs.profiler.staging",
            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        );
        encoder.resolve_query_set(&self.queries, 0..n, &resolved, 0);
        encoder.copy_buffer_to_buffer(&resolved, 0, &staging, 0, u64::from(n) * 8);
        Some(staging)
    }

    /// Adds the timestamps in `staging` (from [`Self::record_resolve`], submitted) to the
    /// kernels' times.
    pub(super) fn add_resolved(
        &mut self,
        ctx: &GpuContext,
        staging: &wgpu::Buffer,
    ) -> Result<(), GpuError> {
        let stamps: Vec<u64> = map_and_read(ctx, staging, self.pending.len() * 2 * 8)?;
        let period = f64::from(ctx.queue.get_timestamp_period());
        for (i, (stage, kernel)) in self.pending.drain(..).enumerate() {
            let ms = stamps[2 * i + 1].saturating_sub(stamps[2 * i]) as f64 * period * 1e-6;
            match self.kernels.iter_mut().find(|k| k.stage == stage && k.kernel == kernel) {
                Some(k) => (k.ms, k.dispatches) = (k.ms + ms, k.dispatches + 1),
                None => self.kernels.push(KernelTime { stage, kernel, ms, dispatches: 1 }),
            }
        }
        Ok(())
    }

    /// Milliseconds per stage, the sum of its kernels', in first-recorded order.
    pub(super) fn stage_times(&self) -> Vec<(&'static str, f64)> {
        let mut stages: Vec<(&'static str, f64)> = Vec::new();
        for k in &self.kernels {
            match stages.iter_mut().find(|(s, _)| *s == k.stage) {
                Some((_, ms)) => *ms += k.ms,
                None => stages.push((k.stage, k.ms)),
            }
        }
        stages
    }
}
