//! Stage `adam` on the GPU (shaders/training/adam.wgsl; twin `trgs_core::reference::adam`): one Adam step
//! of a parameter buffer from its gradient buffer, with the moments in buffers of the same shape.
//! Large buffers are stepped in ranges under the adapter's binding limit.
use crate::layout::AdamParams;
use trgs_core::pipeline::{AdamRate, AdamSettings};
use trgs_render::GpuContext;
use trgs_render::toolkit::gpu::{self, Kernel, Recorder, grid_1d, range};

/// The first and second moments of one parameter buffer.
#[derive(Debug)]
pub struct AdamMoments {
    pub m: wgpu::Buffer,
    pub v: wgpu::Buffer,
    /// Floats per moment.
    pub len: u64,
}

impl AdamMoments {
    /// Zero moments for `len` floats.
    pub fn zeros(ctx: &GpuContext, label: &str, len: u64) -> Self {
        let m = gpu::storage(ctx, &format!("trgs.adam.{label}.m"), len * 4);
        let v = gpu::storage(ctx, &format!("trgs.adam.{label}.v"), len * 4);
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&m, 0, None);
        enc.clear_buffer(&v, 0, None);
        ctx.queue.submit([enc.finish()]);
        Self { m, v, len }
    }
}

impl AdamMoments {
    /// Moments with the given values (after an edit of the Gaussians).
    pub fn from_values(ctx: &GpuContext, label: &str, m: &[f32], v: &[f32]) -> Self {
        Self {
            m: gpu::storage_init(ctx, &format!("trgs.adam.{label}.m"), m),
            v: gpu::storage_init(ctx, &format!("trgs.adam.{label}.v"), v),
            len: m.len() as u64,
        }
    }
}

/// The Adam kernel with its constants.
#[derive(Debug)]
pub struct Adam {
    kernel: Kernel,
    pub settings: AdamSettings,
    /// Floats per binding range (a multiple of 64, so every range offset is 256-byte aligned).
    chunk: u64,
}

impl Adam {
    pub fn new(ctx: &GpuContext, settings: AdamSettings) -> Self {
        // A count must fit the u32 of the uniform and the dispatch.
        let limit = (ctx.binding_limit() / 4).min(1 << 30);
        Self {
            kernel: crate::kernels::TRAINING_KERNELS.adam.build(ctx),
            settings,
            chunk: limit / 64 * 64,
        }
    }

    /// Use at most `floats` per binding range (rounded down to a multiple of 64, at least 64):
    /// tests exercise the split that very large buffers need.
    pub fn set_chunk(&mut self, floats: u64) {
        self.chunk = self.chunk.min((floats / 64 * 64).max(64));
    }

    /// Record step `t` (1-based) with learning rates `rate` of `values` from `grads` (both of
    /// `moments.len` floats), unless `guard` (a [`crate::losses::step_guard`] word) is set when it runs.
    pub fn record(
        &self,
        ctx: &GpuContext,
        rec: &mut Recorder,
        values: &wgpu::Buffer,
        grads: &wgpu::Buffer,
        moments: &AdamMoments,
        rate: &AdamRate,
        t: u32,
        guard: &wgpu::Buffer,
    ) {
        let (bias1, bias2) = self.settings.bias_corrections(t);
        let mut first = 0;
        while first < moments.len {
            let count = self.chunk.min(moments.len - first);
            let params = AdamParams {
                count: count as u32,
                lr: rate.lr as f32,
                beta1: self.settings.beta1 as f32,
                beta2: self.settings.beta2 as f32,
                eps: self.settings.eps as f32,
                bias1: bias1 as f32,
                bias2: bias2 as f32,
                lead: rate.lead,
                stride: rate.stride,
                lead_lr: rate.lead_lr as f32,
                offset: first as u32,
                pad: 0,
            };
            let block = gpu::params(ctx, "trgs.adam.params", &params);
            let (o, n) = (first * 4, count * 4);
            let bind = self.kernel.bind(
                ctx,
                &[
                    block.as_entire_binding(),
                    range(values, o, n),
                    range(grads, o, n),
                    range(&moments.m, o, n),
                    range(&moments.v, o, n),
                    guard.as_entire_binding(),
                ],
            );
            // Four floats a thread (adam.wgsl); the bindings cover the last vec4 whole, since
            // every buffer and binding is padded to 64 bytes and ranges start 256 bytes apart.
            let groups = grid_1d((count as u32).div_ceil(4).div_ceil(256));
            rec.dispatch("adam", &self.kernel, &bind, groups);
            first += count;
        }
    }
}
