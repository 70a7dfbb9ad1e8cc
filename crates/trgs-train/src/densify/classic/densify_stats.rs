//! Stage `densify_stats` on the GPU (shaders/training/densify_stats.wgsl; twin
//! [`DensifyStats::add`]): each step's screen-space gradient norms, observations and screen
//! radii, summed per Gaussian on the GPU. Classic densification reads the sums back once per
//! densification, and a checkpoint reads them when it is written: on a GPU, reading every step's
//! projected records and gradients back costs more than the rest of the step
//! (`bench --train-step` times a step's phases).
use super::settings::DensifyStats;
use crate::layout::DensifyStatsParams;
use trgs_render::toolkit::gpu::{self, Kernel, Recorder, grid_1d};
use trgs_render::toolkit::{FrameStages, GradientStages};
use trgs_render::{Frame, GpuContext, Gradients};

/// Four floats per Gaussian: (sum of gradient norms, observations, largest screen radius, seen
/// in the current step).
const STATS_FLOATS: usize = 4;

/// The statistics since the last densification, on the GPU, with the kernel that adds to them.
#[derive(Debug)]
pub struct GpuDensifyStats {
    kernel: Kernel,
    buffer: wgpu::Buffer,
    len: usize,
}

impl GpuDensifyStats {
    /// Zero statistics for `n` Gaussians.
    pub fn new(ctx: &GpuContext, n: usize) -> Self {
        let kernel = crate::kernels::TRAINING_KERNELS.densify_stats.build(ctx);
        Self { buffer: zeros(ctx, n), kernel, len: n }
    }

    /// These statistics (a checkpoint's), on the GPU.
    pub fn from_stats(ctx: &GpuContext, stats: &DensifyStats) -> Self {
        let mut s = Self::new(ctx, 0);
        s.upload(ctx, stats);
        s
    }

    /// Start over with zero statistics for `n` Gaussians (after the set was edited).
    pub fn reset(&mut self, ctx: &GpuContext, n: usize) {
        self.buffer = zeros(ctx, n);
        self.len = n;
    }

    /// Replace the statistics with `stats`.
    pub fn upload(&mut self, ctx: &GpuContext, stats: &DensifyStats) {
        let data: Vec<[f32; STATS_FLOATS]> = (0..stats.count.len())
            .map(|i| {
                let (g, r) = (stats.grad_sum[i] as f32, stats.max_radius[i] as f32);
                [g, stats.count[i] as f32, r, 0.0]
            })
            .collect();
        self.buffer = gpu::storage_init(ctx, "trgs.densify_stats.stats", &data);
        self.len = stats.count.len();
    }

    /// The statistics on the GPU (`densify_plan` decides from them in place).
    pub fn buffer(&self) -> &wgpu::Buffer {
        &self.buffer
    }

    /// The statistics, read back.
    pub fn read(&self, ctx: &GpuContext) -> Result<DensifyStats, gpu::GpuError> {
        let data: Vec<[f32; STATS_FLOATS]> = gpu::read_buffer(ctx, &self.buffer, 0, self.len)?;
        Ok(DensifyStats {
            grad_sum: data.iter().map(|s| f64::from(s[0])).collect(),
            count: data.iter().map(|s| s[1] as u32).collect(),
            max_radius: data.iter().map(|s| f64::from(s[2])).collect(),
        })
    }

    /// Record the addition of one step: the first `views` passes of `frame` (the camera's, then
    /// mirrored ones) with their screen-space gradients from `grads`.
    pub fn record_add(
        &self,
        ctx: &GpuContext,
        rec: &mut Recorder,
        frame: &Frame,
        grads: &Gradients,
        views: usize,
        guard: &wgpu::Buffer,
    ) {
        let count = self.len as u32;
        // A training step renders the current set before it adds, so the frame always matches;
        // a frame of another set would index other Gaussians' records.
        debug_assert_eq!(frame.gaussian_count(), count, "statistics of another Gaussian set");
        if count == 0 || frame.gaussian_count() != count {
            return;
        }
        let (hw, hh) = (0.5 * frame.width() as f32, 0.5 * frame.height() as f32);
        for (vi, view) in frame.views().iter().enumerate().take(views) {
            let Some(g) = grads.projected_grads(vi) else { continue };
            // One dispatch per page of the projected records and their gradients (a page is
            // one binding's worth).
            let page = view.projected.page_len();
            for first in (0..count).step_by(page as usize) {
                let n = page.min(count - first);
                let params = DensifyStatsParams {
                    count: n,
                    first_pass: u32::from(vi == 0),
                    half_width: hw,
                    half_height: hh,
                };
                let block = gpu::params(ctx, "trgs.densify_stats.params", &params);
                let stats_bytes = STATS_FLOATS as u64 * 4;
                let bind = self.kernel.bind(
                    ctx,
                    &[
                        block.as_entire_binding(),
                        view.projected.range(first, n),
                        g.range(first, n),
                        gpu::range(
                            &self.buffer,
                            u64::from(first) * stats_bytes,
                            u64::from(n) * stats_bytes,
                        ),
                        guard.as_entire_binding(),
                    ],
                );
                rec.dispatch("densify_stats", &self.kernel, &bind, grid_1d(n.div_ceil(256)));
            }
        }
    }
}

fn zeros(ctx: &GpuContext, n: usize) -> wgpu::Buffer {
    gpu::storage_init(ctx, "trgs.densify_stats.stats", &vec![[0.0f32; STATS_FLOATS]; n])
}
