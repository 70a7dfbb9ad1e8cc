//! Small wgpu helpers the stages share: labelled buffers (poison-filled when the context asks for
//! it, so that code relying on zeroed memory fails in tests), readback, compute kernels with their
//! bind groups, and a recorder that puts every dispatch in its own labelled pass with optional
//! timestamp queries.
mod grid;
mod profiler;
mod wait_clock;

use crate::GpuContext;
pub use crate::gpu_error::{ErrorScopes, GpuError, scoped};
pub use grid::{
    STRIDED_GROUPS, STRIDED_GROUPS_CPU, grid_1d, spread_block, spread_step, strided_grid,
    strided_groups_for,
};
pub use profiler::KernelTime;
use profiler::Profiler;
use std::collections::HashMap;
pub use wait_clock::WAIT_SLICE;
use wait_clock::WaitClock;

/// The byte pattern fresh buffers get in poison mode: NaN as f32, 0xffffffff as u32.
pub const POISON_BYTE: u8 = 0xff;

/// Usage of every storage buffer: bound in kernels, copied to readback, cleared, and read as
/// indirect dispatch arguments (the candidate lists' work records).
pub const STORAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST)
    .union(wgpu::BufferUsages::INDIRECT);

/// Bindings may not be empty nor smaller than one element of the largest struct (64 bytes):
/// every size is at least this and a multiple of it.
const MIN_SIZE: u64 = 64;

fn padded(size: u64) -> u64 {
    size.max(MIN_SIZE).div_ceil(MIN_SIZE) * MIN_SIZE
}

/// A new storage buffer of at least `size` bytes, poison-filled in poison mode.
pub fn storage(ctx: &GpuContext, label: &str, size: u64) -> wgpu::Buffer {
    let size = padded(size);
    if ctx.poison_fresh_buffers {
        return filled_at_creation(ctx, label, size, STORAGE, &[], POISON_BYTE);
    }
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: STORAGE,
        mapped_at_creation: false,
    })
}

/// A storage buffer of `words` 32-bit words, at least one (a binding cannot be empty).
pub fn storage_words(ctx: &GpuContext, label: &str, words: u32) -> wgpu::Buffer {
    storage(ctx, label, u64::from(words.max(1)) * 4)
}

/// A buffer of `size` bytes holding `bytes` and then `rest` in every byte after them, written
/// while it is mapped at creation (one copy of the data on the host). When the buffer could not
/// be made (a lost device, no memory left) there is no mapping to write: the buffer is returned
/// unwritten, and the failure reaches the caller through the operation's error scopes or its
/// next wait, not as a panic here (as `wgpu::util::DeviceExt::create_buffer_init` would).
fn filled_at_creation(
    ctx: &GpuContext,
    label: &str,
    size: u64,
    usage: wgpu::BufferUsages,
    bytes: &[u8],
    rest: u8,
) -> wgpu::Buffer {
    let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage,
        mapped_at_creation: true,
    });
    if let Ok(mut view) = buffer.slice(..).get_mapped_range_mut() {
        view.slice(..bytes.len()).copy_from_slice(bytes);
        view.slice(bytes.len()..).fill(rest);
    }
    buffer.unmap();
    buffer
}

/// A storage buffer holding `data` (padded to the minimum size with zeros). The data is copied
/// once, into the buffer mapped at creation: a padded copy made first doubled the host traffic
/// of every upload, e.g. the whole state after each densification.
pub fn storage_init<T: bytemuck::Pod>(ctx: &GpuContext, label: &str, data: &[T]) -> wgpu::Buffer {
    let bytes = bytemuck::cast_slice::<T, u8>(data);
    filled_at_creation(ctx, label, padded(bytes.len() as u64), STORAGE, bytes, 0)
}

/// A dispatch's parameter block holding `value`, bound as `var<storage, read>`.
///
/// Not a uniform buffer on purpose: lavapipe inlines uniform values that steer control flow into
/// the shader and recompiles it (LLVM, 0.1 to 0.5 s) for every new set of values, e.g. every
/// mirrored view of a moving plane; a storage buffer is never inlined. Real GPUs read a small
/// block shared by all threads equally fast from either.
pub fn params<T: bytemuck::Pod>(ctx: &GpuContext, label: &str, value: &T) -> wgpu::Buffer {
    let bytes = bytemuck::bytes_of(value);
    // COPY_DST: a field may come from the GPU (the depth order's entry count, copied in).
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
    // Mapped at creation, the size must be a multiple of 4 (every parameter block is).
    let size = (bytes.len() as u64).div_ceil(4) * 4;
    filled_at_creation(ctx, label, size, usage, bytes, 0)
}

/// A buffer of `size` bytes to copy GPU results into and map for reading ([`PendingRead`],
/// [`map_and_read`]).
pub fn staging(ctx: &GpuContext, label: &str, size: u64) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// Read `count` values of `T` from `buffer` at byte `offset` (blocking).
pub fn read_buffer<T: bytemuck::Pod>(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    offset: u64,
    count: usize,
) -> Result<Vec<T>, GpuError> {
    let bytes = (count * std::mem::size_of::<T>()) as u64;
    if bytes == 0 {
        return Ok(Vec::new());
    }
    let size = bytes.div_ceil(4) * 4;
    // The staging buffer and the copy may fail too (no memory left, a lost device).
    let scopes = ErrorScopes::open(ctx, "copying a buffer for readback");
    let staging = staging(ctx, "trgs.readback.staging", size);
    let mut enc = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("trgs.readback") });
    enc.copy_buffer_to_buffer(buffer, offset, &staging, 0, size);
    ctx.queue.submit([enc.finish()]);
    // Closed before the mapping, so that a staging buffer that could not be made is reported as
    // the lack of memory it is, not as the mapping wgpu then refuses.
    scopes.close()?;
    map_and_read(ctx, &staging, bytes as usize)
}

/// The longest the CPU waits for submitted GPU work before it gives up: far beyond any frame or
/// training step, even of large scenes on a CPU adapter (`bench` times them), so that a hung
/// kernel or a device that stopped answering ends in a [`GpuError`] that says so instead of a
/// process that never returns.
pub const GPU_WAIT_LIMIT: std::time::Duration = std::time::Duration::from_secs(300);

/// The wait limit in force: `GPU_WAIT_LIMIT`, or `TRGS_GPU_WAIT_SECONDS` from the environment (a
/// whole number of seconds, one or more), so that a hunt for a hang can end each stuck wait in
/// an error that names it well within a test runner's own time limit.
pub fn gpu_wait_limit() -> std::time::Duration {
    static LIMIT: std::sync::OnceLock<std::time::Duration> = std::sync::OnceLock::new();
    *LIMIT.get_or_init(|| {
        std::env::var("TRGS_GPU_WAIT_SECONDS")
            .ok()
            .and_then(|v| v.trim().parse::<u64>().ok())
            .filter(|&s| s >= 1)
            .map_or(GPU_WAIT_LIMIT, std::time::Duration::from_secs)
    })
}

/// Block until the GPU has finished everything submitted so far, at most [`gpu_wait_limit`];
/// `what` names the wait in the error when the device is lost or does not finish in time.
///
/// A driver that reports the device lost (or out of memory) while it is waited for makes
/// `wgpu::Device::poll` panic, not return an error (wgpu 30); that panic is caught here and
/// returned as [`GpuError::Lost`] (the panic hook still prints its message). The device is gone
/// by then, so no state that could be used afterwards is left half-updated.
pub fn wait_for_gpu(ctx: &GpuContext, what: &str) -> Result<(), GpuError> {
    wait_for_submission(ctx, what, None)
}

/// [`wait_for_gpu`] for `submission` and what was submitted before it (everything when None):
/// work submitted after it may still be running when this returns. Counted in
/// [`GpuContext::waits`].
///
/// The limit is of time the process ran: the wait is made of slices of at most [`WAIT_SLICE`],
/// and a slice counts for no more than its length however long it took on the clock. A run
/// stopped by job control (Ctrl-Z, SIGSTOP) or a machine put to sleep in the middle of a step
/// otherwise finds, when it goes on, that the limit passed while nothing ran, and ends in a
/// hung-kernel error.
pub fn wait_for_submission(
    ctx: &GpuContext,
    what: &str,
    submission: Option<wgpu::SubmissionIndex>,
) -> Result<(), GpuError> {
    ctx.count_wait();
    let limit = gpu_wait_limit();
    let lost = |detail: String| {
        crate::gpu_error::lost(&format!("waiting for {what}"), ctx.lost().unwrap_or(detail))
    };
    let mut waited = WaitClock::new(limit);
    while let Some(slice) = waited.next_slice() {
        let wait =
            wgpu::PollType::Wait { submission_index: submission.clone(), timeout: Some(slice) };
        let polled =
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| ctx.device.poll(wait)));
        match polled {
            Ok(Ok(_)) => return Ok(()),
            Ok(Err(wgpu::PollError::Timeout)) => waited.add(slice),
            Ok(Err(e)) => return Err(lost(e.to_string())),
            Err(panic) => {
                let message = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_else(|| "wgpu stopped while polling the device".to_string());
                return Err(lost(message));
            }
        }
    }
    Err(GpuError::Timeout { what: what.to_string(), seconds: limit.as_secs() })
}

const READBACK: &str = "reading back a buffer";

/// The mapping of a MAP_READ buffer whose copies have been submitted, started without waiting
/// for the GPU: read it when the values are needed ([`PendingRead::read`]), by when the work
/// before it may have finished.
#[derive(Debug)]
pub struct PendingRead {
    staging: wgpu::Buffer,
    mapped: std::sync::Arc<std::sync::OnceLock<Result<(), wgpu::BufferAsyncError>>>,
    /// The submission that copies into `staging`, when known: a read then waits for it alone,
    /// not for work submitted after it.
    submission: Option<wgpu::SubmissionIndex>,
}

impl PendingRead {
    /// Starts mapping `staging`: call after the submission that copies into it.
    pub fn start(staging: wgpu::Buffer) -> Self {
        let mapped = std::sync::Arc::new(std::sync::OnceLock::new());
        let done = std::sync::Arc::clone(&mapped);
        staging.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            let _ = done.set(r);
        });
        Self { staging, mapped, submission: None }
    }

    /// Starts mapping `staging`, which `submission` copies into: reading it waits for that
    /// submission only, so a step read back after the next one was submitted leaves the GPU
    /// busy with the next one.
    pub fn after(staging: wgpu::Buffer, submission: wgpu::SubmissionIndex) -> Self {
        Self { submission: Some(submission), ..Self::start(staging) }
    }

    /// The first `bytes` bytes, waiting for the GPU only if the mapping has not completed.
    pub fn read<T: bytemuck::Pod>(
        self,
        ctx: &GpuContext,
        bytes: usize,
    ) -> Result<Vec<T>, GpuError> {
        let (waited, mapped) = self.wait(ctx);
        waited?;
        mapped.map_err(|detail| lost_reading(ctx, detail))?;
        self.take(ctx, bytes)
    }

    /// Waits for the GPU unless the mapping has completed (its callback runs inside a poll of
    /// the device): the wait's result, then the mapping's. A lost device (or a buffer that could
    /// not be allocated) surfaces as a failed mapping, not as values that were never computed.
    fn wait(&self, ctx: &GpuContext) -> (Result<(), GpuError>, Result<(), String>) {
        let waited = match self.mapped.get() {
            Some(_) => Ok(()),
            None => wait_for_submission(ctx, "its work before a readback", self.submission.clone()),
        };
        let mapped = match self.mapped.get() {
            Some(Ok(())) => Ok(()),
            Some(Err(e)) => Err(e.to_string()),
            None => Err("the mapping never completed".to_string()),
        };
        (waited, mapped)
    }

    /// The mapped bytes, then unmaps.
    fn take<T: bytemuck::Pod>(self, ctx: &GpuContext, bytes: usize) -> Result<Vec<T>, GpuError> {
        let out = {
            let slice = self.staging.slice(..);
            let view = slice.get_mapped_range().map_err(|e| lost_reading(ctx, e.to_string()))?;
            bytemuck::pod_collect_to_vec(&view[..bytes])
        };
        self.staging.unmap();
        ctx.count_read(bytes);
        Ok(out)
    }
}

/// A readback that failed for `detail`, or for the device's loss when it was lost.
fn lost_reading(ctx: &GpuContext, detail: String) -> GpuError {
    crate::gpu_error::lost(READBACK, ctx.lost().unwrap_or(detail))
}

/// Map a MAP_READ buffer whose copy has been submitted, and read its first `bytes` bytes.
pub fn map_and_read<T: bytemuck::Pod>(
    ctx: &GpuContext,
    staging: &wgpu::Buffer,
    bytes: usize,
) -> Result<Vec<T>, GpuError> {
    let scopes = ErrorScopes::open(ctx, READBACK);
    let pending = PendingRead::start(staging.clone());
    let (waited, mapped) = pending.wait(ctx);
    // Most specific first: what wgpu refused (or the loss behind it), a wait that failed, then
    // a mapping that failed without either.
    scopes.close()?;
    waited?;
    mapped.map_err(|detail| lost_reading(ctx, detail))?;
    pending.take(ctx, bytes)
}

/// A compute pipeline with the layout derived from its WGSL.
#[derive(Debug)]
pub struct Kernel {
    pub name: &'static str,
    pub pipeline: wgpu::ComputePipeline,
    pub layout: wgpu::BindGroupLayout,
}

impl Kernel {
    /// The pipeline of `wgsl` (a whole shader, prelude included, with entry point `main`),
    /// labelled `name`. Kernels are built from their registration
    /// ([`super::registry::KernelSpec::build`]).
    pub fn from_wgsl(ctx: &GpuContext, name: &'static str, wgsl: String) -> Self {
        let text = wgsl;
        let module = ctx.device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(&format!("trgs.{name}.module")),
            source: wgpu::ShaderSource::Wgsl(text.into()),
        });
        let pipeline = ctx.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(&format!("trgs.{name}.pipeline")),
            layout: None,
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
        let layout = pipeline.get_bind_group_layout(0);
        Self { name, pipeline, layout }
    }

    /// A bind group of `resources` at bindings 0, 1, ...
    pub fn bind(
        &self,
        ctx: &GpuContext,
        resources: &[wgpu::BindingResource<'_>],
    ) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry<'_>> = resources
            .iter()
            .enumerate()
            .map(|(i, r)| wgpu::BindGroupEntry { binding: i as u32, resource: r.clone() })
            .collect();
        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&format!("trgs.{}.bind", self.name)),
            layout: &self.layout,
            entries: &entries,
        })
    }
}

/// A byte range of a buffer as a binding.
pub fn range(buffer: &wgpu::Buffer, offset: u64, size: u64) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
        buffer,
        offset,
        size: wgpu::BufferSize::new(padded(size).min(buffer.size() - offset)),
    })
}

/// Records dispatches into one command encoder.
#[derive(Debug)]
pub struct Recorder {
    pub encoder: wgpu::CommandEncoder,
    profiler: Option<Profiler>,
}

impl Recorder {
    /// A new encoder; `profile` adds timestamp queries when the adapter has them.
    pub fn new(ctx: &GpuContext, label: &str, profile: bool) -> Self {
        let encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
        let profiler = (profile && ctx.capabilities.timestamps).then(|| Profiler::new(ctx));
        Self { encoder, profiler }
    }

    /// Record one dispatch of `kernel` in its own pass, labelled and timed as `stage`.
    pub fn dispatch(
        &mut self,
        stage: &'static str,
        kernel: &Kernel,
        bind: &wgpu::BindGroup,
        groups: [u32; 3],
    ) {
        if groups.contains(&0) {
            return;
        }
        self.pass(stage, kernel, bind).dispatch_workgroups(groups[0], groups[1], groups[2]);
    }

    /// Record one dispatch of `kernel` whose workgroup counts a kernel wrote into `args` at byte
    /// `offset` (three u32), in its own pass, labelled and timed as `stage`.
    pub fn dispatch_indirect(
        &mut self,
        stage: &'static str,
        kernel: &Kernel,
        bind: &wgpu::BindGroup,
        args: &wgpu::Buffer,
        offset: u64,
    ) {
        self.pass(stage, kernel, bind).dispatch_workgroups_indirect(args, offset);
    }

    /// A new compute pass labelled and timed as `stage`, with `kernel` and `bind` set.
    fn pass(
        &mut self,
        stage: &'static str,
        kernel: &Kernel,
        bind: &wgpu::BindGroup,
    ) -> wgpu::ComputePass<'_> {
        let timestamp_writes =
            self.profiler.as_mut().and_then(|p| p.timestamp_writes(stage, kernel.name));
        let mut pass = self.encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(stage),
            timestamp_writes,
        });
        pass.set_pipeline(&kernel.pipeline);
        pass.set_bind_group(0, bind, &[]);
        pass
    }

    /// Submit the recorded work and wait for it; with profiling, add this submission's stage
    /// times. Leaves a fresh encoder for what follows.
    pub fn submit_and_wait(&mut self, ctx: &GpuContext) -> Result<(), GpuError> {
        self.submit_then(ctx, true).map(drop)
    }

    /// Submit the recorded work without waiting for it, unless profiling (whose stage times
    /// are read back). Leaves a fresh encoder for what follows.
    pub fn submit(&mut self, ctx: &GpuContext) -> Result<wgpu::SubmissionIndex, GpuError> {
        self.submit_then(ctx, false)
    }

    fn submit_then(
        &mut self,
        ctx: &GpuContext,
        wait: bool,
    ) -> Result<wgpu::SubmissionIndex, GpuError> {
        let staging = self.profiler.as_ref().and_then(|p| p.record_resolve(ctx, &mut self.encoder));
        let encoder = std::mem::replace(
            &mut self.encoder,
            ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("trgs.recorder"),
            }),
        );
        let index = ctx.queue.submit([encoder.finish()]);
        if let (Some(p), Some(staging)) = (&mut self.profiler, staging) {
            p.add_resolved(ctx, &staging)?;
        } else if wait {
            wait_for_gpu(ctx, "a recorded batch of passes")?;
        }
        Ok(index)
    }

    /// Submit the recorded work with a copy of the first `count` values of `buffer` behind it,
    /// and read them back: one wait, where a submission waited for and a separate readback make
    /// two (the deciding stages' counters).
    pub fn submit_and_read<T: bytemuck::Pod>(
        &mut self,
        ctx: &GpuContext,
        buffer: &wgpu::Buffer,
        count: usize,
    ) -> Result<Vec<T>, GpuError> {
        let bytes = count * std::mem::size_of::<T>();
        self.submit_read(ctx, buffer, bytes)?.read(ctx, bytes)
    }

    /// Submit the recorded work with a copy of the first `bytes` bytes of `buffer` behind it,
    /// without waiting: the readback to take later (the counters a trainer reads a step late).
    pub fn submit_read(
        &mut self,
        ctx: &GpuContext,
        buffer: &wgpu::Buffer,
        bytes: usize,
    ) -> Result<PendingRead, GpuError> {
        let size = (bytes as u64).div_ceil(4).max(1) * 4;
        let staging = staging(ctx, "trgs.readback.staging", size);
        if bytes > 0 {
            self.encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
        }
        let submission = self.submit(ctx)?;
        Ok(PendingRead::after(staging, submission))
    }

    /// Milliseconds per stage (in first-recorded order), when profiling.
    pub fn stage_times(&self) -> Option<Vec<(&'static str, f64)>> {
        self.profiler.as_ref().map(Profiler::stage_times)
    }

    /// Milliseconds per kernel within each stage (in first-recorded order), when profiling.
    pub fn kernel_times(&self) -> Option<Vec<KernelTime>> {
        self.profiler.as_ref().map(|p| p.kernels.clone())
    }
}

/// Grow-only named buffers, so that rendering the next frame into the same [`crate::Frame`]
/// reuses its allocations.
#[derive(Debug, Default)]
pub struct BufferPool {
    buffers: HashMap<String, wgpu::Buffer>,
}

impl BufferPool {
    /// The buffer `label` with at least `size` bytes (new and, in poison mode, poisoned when it
    /// had to grow).
    pub fn get(&mut self, ctx: &GpuContext, label: &str, size: u64) -> wgpu::Buffer {
        let grown = match self.buffers.get(label) {
            Some(b) if b.size() >= padded(size) => return b.clone(),
            // A buffer that grows once usually grows again (key counts creep up as the camera
            // moves): a quarter of headroom, within what one binding and one buffer can hold.
            Some(_) => {
                let limits = ctx.device.limits();
                // storage() pads to 64 bytes: cap below the limit after padding.
                let most = ctx.binding_limit().min(limits.max_buffer_size);
                (size + size / 4).min(most / 64 * 64).max(size)
            }
            None => size,
        };
        let b = storage(ctx, label, grown);
        self.buffers.insert(label.to_string(), b.clone());
        b
    }

    /// Total bytes held.
    pub fn bytes(&self) -> u64 {
        self.buffers.values().map(wgpu::Buffer::size).sum()
    }
}
