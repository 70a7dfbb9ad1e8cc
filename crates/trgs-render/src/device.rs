//! Device setup: pick the best adapter, enable the optional features it has (float atomics,
//! subgroups, timestamp queries) and record which ones the stages may use, so that each stage can
//! choose its fast path or its fallback.
use crate::layout::{
    SCAN_ITEMS, SCAN_ITEMS_WIDE, SCAN_THREADS, SORT_ITEMS, SORT_ITEMS_WIDE, SORT_THREADS,
};
use wgpu::{Features, Limits};

#[derive(Debug, thiserror::Error)]
pub enum DeviceError {
    #[error(
        "no GPU adapter found (wgpu saw none on Vulkan/Metal/DX12). On Linux without a GPU install \
         Mesa's CPU Vulkan driver lavapipe: `apt-get install mesa-vulkan-drivers` \
         (scripts/ensure-vulkan.sh does this as root)"
    )]
    NoAdapter,
    #[error("no adapter matches TRGS_ADAPTER={wanted:?}; available: {available}")]
    NoMatchingAdapter { wanted: String, available: String },
    #[error("the adapter {adapter} refused a device: {source}")]
    RequestDevice { adapter: String, source: wgpu::RequestDeviceError },
    /// A device with a limit below what the kernels need: an adapter that offers no more (the
    /// descriptor asks for all it offers), or a device created elsewhere
    /// ([`GpuContext::from_device`]) without [`device_descriptor`].
    #[error(
        "the device allows {have} {what}, trgs's kernels need {need}: choose another GPU with \
         TRGS_ADAPTER (an app that creates the device itself: from \
         trgs_render::device_descriptor, which asks for all the adapter offers)"
    )]
    Limit { what: &'static str, have: u32, need: u32 },
}

/// The most storage buffers one trgs kernel binds (`project_bwd`), above WebGPU's default of 8:
/// a device must allow this many per shader stage (a test checks every shader against it).
pub const STORAGE_BUFFERS_PER_STAGE: u32 = 17;

/// How `rasterize_reflection` and the adjoints of both passes (`rasterize_bwd`,
/// `rasterize_reflection_bwd`) give a tile's pixels to threads. (`rasterize` keeps one pixel per
/// thread everywhere: it was slower on lavapipe in four rows.)
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TileLayout {
    /// One pixel per thread: what fills a GPU.
    #[default]
    PixelPerThread,
    /// Several rows of one tile column per thread, for CPU adapters: four in
    /// `rasterize_reflection`, the column's eight in the adjoints. There a workgroup's subgroups
    /// (SIMD vectors) run one after another, each paying its loads of a batch entry and loop
    /// control however few of its pixels still blend, and a subgroup reduction and its atomics
    /// are loops over the lanes: the rows share all of these, and with eight an adjoint's
    /// subgroup is the whole tile, one reduction per entry. (Eight rows made
    /// `rasterize_reflection` slower: `train --profile` on the built-in scene.)
    RowsPerThread,
}

impl TileLayout {
    /// The layout that is faster on an adapter of this type.
    pub fn for_adapter(device_type: wgpu::DeviceType) -> Self {
        match device_type {
            wgpu::DeviceType::Cpu => Self::RowsPerThread,
            _ => Self::PixelPerThread,
        }
    }
}

/// How many values a workgroup of the prefix sum and the radix sort takes (`prefix_sum`,
/// `sort_count`, `sort_scatter`; constants in `layout.rs`, the WGSL side in
/// `shaders/shared/block_width.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BlockWidth {
    /// `SCAN_ITEMS` values per thread in the scan, `SORT_ITEMS` keys in a radix pass: as many
    /// workgroups as a frame's keys give, to spread over a GPU's cores, and few registers per
    /// thread.
    #[default]
    Narrow,
    /// `SCAN_ITEMS_WIDE` and `SORT_ITEMS_WIDE`, four times as many, for CPU adapters. There each
    /// workgroup pays its barriers while its serial loops are cheap, and the sort and scans take
    /// less time (`bench` on lavapipe, and docs/gpu-renderer.md).
    Wide,
}

impl BlockWidth {
    /// The width that is faster on an adapter of this type.
    pub fn for_adapter(device_type: wgpu::DeviceType) -> Self {
        match device_type {
            wgpu::DeviceType::Cpu => Self::Wide,
            _ => Self::Narrow,
        }
    }

    /// Values per workgroup of the prefix sum.
    pub fn scan_block(self) -> u32 {
        SCAN_THREADS * self.scan_items()
    }

    /// Values per thread of the prefix sum.
    pub fn scan_items(self) -> u32 {
        match self {
            Self::Narrow => SCAN_ITEMS,
            Self::Wide => SCAN_ITEMS_WIDE,
        }
    }

    /// Keys per workgroup (block) of a radix pass.
    pub fn sort_block(self) -> u32 {
        SORT_THREADS * self.sort_items()
    }

    /// Keys per thread of a radix pass.
    pub fn sort_items(self) -> u32 {
        match self {
            Self::Narrow => SORT_ITEMS,
            Self::Wide => SORT_ITEMS_WIDE,
        }
    }
}

/// Optional features the adapter granted, and how the kernels use the device.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Capabilities {
    /// `atomicAdd` on f32 in storage buffers (gradient accumulation without compare-exchange).
    pub float_atomics: bool,
    /// Subgroup operations (reductions before atomics).
    pub subgroups: bool,
    /// Timestamp queries (per-stage timings in benchmarks).
    pub timestamps: bool,
    /// Pixels per thread of the per-tile kernels that have a choice ([`TileLayout`]).
    pub tile_layout: TileLayout,
    /// Values per workgroup of the prefix sum and the radix sort ([`BlockWidth`]).
    pub block_width: BlockWidth,
    /// The rasterize passes walk each pixel block's entries only, by chunks of the subgroup's
    /// lanes with broadcasts (shaders/shared/block_walk.wgsl, the define `BLOCK_WALK`): on by
    /// default where subgroups hold at most 8 lanes, so that a subgroup lies in one block and
    /// skips together. On a CPU adapter a subgroup is one SIMD vector, which otherwise pays for
    /// every entry of its tile's list, reaching its pixels or not, and for every read of
    /// workgroup memory lane by lane.
    pub block_walk: bool,
    /// Workgroups of a strided dispatch at most ([`crate::gpu::strided_grid`]).
    pub strided_groups: u32,
    /// Whether work is recorded while the device runs what was submitted before it. On a GPU
    /// that keeps it busy; a CPU adapter runs the work on the cores that would record the next,
    /// where recording only slows its threads down (`bench --train-step` with
    /// `TRGS_RECORD_WHILE_BUSY=1`, docs/BENCHMARKS.md), so a training step there lets the queue
    /// drain at the end of each phase instead. Readbacks stay asynchronous either way.
    pub records_while_busy: bool,
}

/// How to choose the device.
#[derive(Clone, Debug, Default)]
pub struct DeviceOptions {
    /// Use the first adapter whose name or PCI bus address (`0000:1b:00.0`) contains this
    /// (case-insensitive); also read from the environment variable `TRGS_ADAPTER` when None.
    /// The address tells apart the identical GPUs of one machine (a cluster task is handed one
    /// of them: python/trgs_ray).
    pub adapter_name: Option<String>,
    /// Never enable the optional features (tests of the fallback paths).
    pub disable_optional_features: bool,
    /// Fill every buffer the renderer allocates with 0xff bytes (NaN as f32), so that code that
    /// relies on zeroed memory fails; also on when the environment sets `TRGS_POISON_BUFFERS=1`.
    pub poison_fresh_buffers: bool,
    /// The layout of the per-tile kernels that have a choice; None: the faster one for the adapter
    /// ([`TileLayout::for_adapter`]). Tests on a CPU adapter set it to check the GPU's too.
    pub tile_layout: Option<TileLayout>,
    /// The width of the scan and sort blocks; None: the faster one for the adapter
    /// ([`BlockWidth::for_adapter`]). Tests on a CPU adapter set it to check the GPU's too.
    pub block_width: Option<BlockWidth>,
    /// Whether the rasterize passes walk by pixel blocks ([`Capabilities::block_walk`]); None:
    /// where the adapter's subgroups hold at most 8 lanes. Some(true) still needs subgroups
    /// (without them it is off); with wider ones the chunks take 8 of their lanes.
    pub block_walk: Option<bool>,
    /// Workgroups of a strided dispatch at most; None: the adapter's
    /// ([`crate::gpu::strided_groups_for`]). Tests set a few, so that each workgroup takes
    /// several blocks.
    pub strided_groups: Option<u32>,
    /// [`Capabilities::records_while_busy`]; None: as the environment sets
    /// `TRGS_RECORD_WHILE_BUSY` (1 or 0), else on any adapter but a CPU one. Tests on a CPU
    /// adapter set it to check that a step records without waiting.
    pub records_while_busy: Option<bool>,
}

/// A wgpu device and queue with what they can do. Cloning shares the device.
#[derive(Clone, Debug)]
pub struct GpuContext {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pub capabilities: Capabilities,
    /// See [`DeviceOptions::poison_fresh_buffers`].
    pub poison_fresh_buffers: bool,
    /// Why the device was lost, once it has been (set by its device-lost callback).
    loss: DeviceLoss,
    /// See [`GpuContext::binding_limit`].
    binding_limit: u64,
    /// See [`GpuContext::waits`].
    waits: std::sync::Arc<std::sync::atomic::AtomicU64>,
    /// Bytes read back so far ([`GpuContext::bytes_read`]).
    bytes_read: std::sync::Arc<std::sync::atomic::AtomicU64>,
}

/// Where a device's lost callback leaves its reason, shared by every clone of the context.
#[derive(Clone, Debug, Default)]
pub(crate) struct DeviceLoss(std::sync::Arc<std::sync::Mutex<Option<String>>>);

impl DeviceLoss {
    fn record(&self, reason: wgpu::DeviceLostReason, message: &str) {
        if let Ok(mut slot) = self.0.lock() {
            slot.get_or_insert_with(|| match message {
                "" => format!("{reason:?}"),
                m => format!("{reason:?}: {m}"),
            });
        }
    }

    pub(crate) fn reason(&self) -> Option<String> {
        self.0.lock().ok().and_then(|slot| slot.clone())
    }
}

const OPTIONAL: [(Features, &str); 3] = [
    (Features::SHADER_FLOAT32_ATOMIC, "float_atomics"),
    (Features::SUBGROUP, "subgroups"),
    (Features::TIMESTAMP_QUERY, "timestamps"),
];

/// Rank adapters: discrete GPU, integrated, virtual, then CPU (lavapipe).
fn rank(info: &wgpu::AdapterInfo) -> u8 {
    match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

/// The adapter named by `options.adapter_name` or `TRGS_ADAPTER` (a case-insensitive part of its
/// name or PCI bus address), else the best: discrete, integrated, virtual, other, then CPU.
pub fn pick_adapter(
    mut adapters: Vec<wgpu::Adapter>,
    options: &DeviceOptions,
) -> Result<wgpu::Adapter, DeviceError> {
    if adapters.is_empty() {
        return Err(DeviceError::NoAdapter);
    }
    adapters.sort_by_key(|a| rank(&a.get_info()));
    let wanted = options.adapter_name.clone().or_else(|| std::env::var("TRGS_ADAPTER").ok());
    let Some(w) = wanted else {
        return Ok(adapters.swap_remove(0));
    };
    let infos: Vec<wgpu::AdapterInfo> = adapters.iter().map(wgpu::Adapter::get_info).collect();
    match infos.iter().position(|i| adapter_matches(&i.name, &i.device_pci_bus_id, &w)) {
        Some(p) => Ok(adapters.swap_remove(p)),
        None => {
            let available: Vec<String> = infos
                .iter()
                .map(|i| match i.device_pci_bus_id.as_str() {
                    "" => i.name.clone(),
                    bus => format!("{} ({bus})", i.name),
                })
                .collect();
            Err(DeviceError::NoMatchingAdapter { wanted: w, available: available.join(", ") })
        }
    }
}

/// Whether `wanted` is a case-insensitive part of an adapter's name or of its PCI bus address.
fn adapter_matches(name: &str, pci_bus_id: &str, wanted: &str) -> bool {
    let wanted = wanted.to_lowercase();
    name.to_lowercase().contains(&wanted)
        || (!pci_bus_id.is_empty() && pci_bus_id.to_lowercase().contains(&wanted))
}

/// The device trgs asks `adapter` for: the optional features it has (unless disabled) and every
/// limit it offers (storage bindings of 128 MiB and more matter for large scenes).
pub fn device_descriptor(
    adapter: &wgpu::Adapter,
    options: &DeviceOptions,
) -> wgpu::DeviceDescriptor<'static> {
    let mut features = Features::empty();
    if !options.disable_optional_features {
        for (f, _) in OPTIONAL {
            if adapter.features().contains(f) {
                features |= f;
            }
        }
    }
    let limits: Limits = adapter.limits();
    wgpu::DeviceDescriptor {
        label: Some("trgs.device"),
        required_features: features,
        required_limits: limits,
        ..Default::default()
    }
}

impl GpuContext {
    /// The best adapter with default options (blocking).
    pub fn new() -> Result<Self, DeviceError> {
        Self::with_options(&DeviceOptions::default())
    }

    pub fn with_options(options: &DeviceOptions) -> Result<Self, DeviceError> {
        pollster::block_on(Self::create(options))
    }

    async fn create(options: &DeviceOptions) -> Result<Self, DeviceError> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::PRIMARY,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        let adapters = instance.enumerate_adapters(wgpu::Backends::PRIMARY).await;
        let adapter = pick_adapter(adapters, options)?;
        let info = adapter.get_info();
        let (device, queue) =
            adapter.request_device(&device_descriptor(&adapter, options)).await.map_err(
                |source| DeviceError::RequestDevice { adapter: info.name.clone(), source },
            )?;
        Self::from_device(adapter, device, queue, options)
    }

    /// A context on a device created elsewhere (e.g. by a UI toolkit that also presents to a
    /// window), from [`device_descriptor`] so that it has the features trgs uses.
    ///
    /// Sets the device's lost callback (replacing one the app set before), so that work on a
    /// lost device fails with [`crate::GpuError::Lost`] and its reason.
    pub fn from_device(
        adapter: wgpu::Adapter,
        device: wgpu::Device,
        queue: wgpu::Queue,
        options: &DeviceOptions,
    ) -> Result<Self, DeviceError> {
        // Checked here, not when a pipeline fails to build (a validation panic).
        let have = device.limits().max_storage_buffers_per_shader_stage;
        if have < STORAGE_BUFFERS_PER_STAGE {
            return Err(DeviceError::Limit {
                what: "storage buffers per shader stage",
                have,
                need: STORAGE_BUFFERS_PER_STAGE,
            });
        }
        let features = device.features();
        let capabilities = Capabilities {
            float_atomics: features.contains(Features::SHADER_FLOAT32_ATOMIC),
            subgroups: features.contains(Features::SUBGROUP),
            timestamps: features.contains(Features::TIMESTAMP_QUERY),
            tile_layout: options
                .tile_layout
                .unwrap_or_else(|| TileLayout::for_adapter(adapter.get_info().device_type)),
            block_width: options
                .block_width
                .unwrap_or_else(|| BlockWidth::for_adapter(adapter.get_info().device_type)),
            block_walk: features.contains(Features::SUBGROUP)
                && options.block_walk.unwrap_or_else(|| {
                    let info = adapter.get_info();
                    info.subgroup_max_size > 0 && info.subgroup_max_size <= 8
                }),
            strided_groups: options
                .strided_groups
                .unwrap_or_else(|| crate::gpu::strided_groups_for(adapter.get_info().device_type))
                .clamp(1, crate::layout::MAX_WORKGROUPS),
            records_while_busy: options
                .records_while_busy
                .or_else(|| match std::env::var("TRGS_RECORD_WHILE_BUSY").as_deref() {
                    Ok("1") => Some(true),
                    Ok("0") => Some(false),
                    _ => None,
                })
                .unwrap_or(adapter.get_info().device_type != wgpu::DeviceType::Cpu),
        };
        let poison_fresh_buffers = options.poison_fresh_buffers
            || std::env::var("TRGS_POISON_BUFFERS").is_ok_and(|v| v == "1");
        let info = adapter.get_info();
        let loss = DeviceLoss::default();
        let on_loss = loss.clone();
        device.set_device_lost_callback(move |reason, message| on_loss.record(reason, &message));
        let binding_limit = device.limits().max_storage_buffer_binding_size;
        Ok(Self {
            adapter,
            device,
            queue,
            info,
            capabilities,
            poison_fresh_buffers,
            loss,
            binding_limit,
            waits: Default::default(),
            bytes_read: Default::default(),
        })
    }

    /// The most bytes of a buffer one storage binding may hold (the device's
    /// `max_storage_buffer_binding_size`): what every stage sizes its chunks, pages and refusals
    /// by.
    pub fn binding_limit(&self) -> u64 {
        self.binding_limit
    }

    /// How many times the CPU has blocked on this device so far (every wait for submitted work,
    /// whether for a readback or a submission): how tests show that work is recorded without
    /// waiting.
    pub fn waits(&self) -> u64 {
        self.waits.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Counts one wait ([`GpuContext::waits`]).
    pub(crate) fn count_wait(&self) {
        self.waits.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    }

    /// How many bytes every readback from this device has returned so far: how tests show that
    /// a stage decides on the GPU without reading the Gaussians back.
    pub fn bytes_read(&self) -> u64 {
        self.bytes_read.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Counts `bytes` read back ([`GpuContext::bytes_read`]).
    pub(crate) fn count_read(&self, bytes: usize) {
        self.bytes_read.fetch_add(bytes as u64, std::sync::atomic::Ordering::Relaxed);
    }

    /// Why the device was lost, if it has been (known once the GPU was last waited for).
    pub fn lost(&self) -> Option<String> {
        self.loss.reason()
    }

    /// The adapter for users: its name, backend and kind.
    pub fn adapter(&self) -> String {
        format!("{} ({:?}, {:?})", self.info.name, self.info.backend, self.info.device_type)
    }

    /// One line for logs and benchmarks: adapter, backend, optional features and the layout
    /// choices made for them.
    pub fn describe(&self) -> String {
        let on: Vec<&str> = OPTIONAL
            .iter()
            .filter(|(f, _)| self.device.features().contains(*f))
            .map(|(_, n)| *n)
            .collect();
        format!(
            "{} ({:?}, {:?}); optional features: [{}]; tile layout: {:?}; scan and sort blocks: {:?}; block walk: {}",
            self.info.name,
            self.info.backend,
            self.info.device_type,
            on.join(", "),
            self.capabilities.tile_layout,
            self.capabilities.block_width,
            if self.capabilities.block_walk { "on" } else { "off" },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::adapter_matches;

    #[test]
    fn an_adapter_is_chosen_by_a_part_of_its_name_or_bus_address() {
        let (h200, bus) = ("NVIDIA H200", "0000:1b:00.0");
        assert!(adapter_matches(h200, bus, "h200"));
        // nvidia-smi writes the address in capitals with a longer domain; its bus, device and
        // function are what python/trgs_ray passes.
        assert!(adapter_matches(h200, bus, "1B:00.0"));
        assert!(!adapter_matches(h200, bus, "1c:00.0"));
        // Lavapipe has no address: only its name matches.
        assert!(adapter_matches("llvmpipe (LLVM 15.0.6, 256 bits)", "", "llvmpipe"));
        assert!(!adapter_matches("llvmpipe (LLVM 15.0.6, 256 bits)", "", ":"));
    }
}
