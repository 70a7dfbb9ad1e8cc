//! The training views' photos on the GPU, under a memory budget.
//!
//! Every view's photo is held in RAM at 8 bits ([`crate::data::View`]); its GPU copy (a
//! [`GpuTarget`], 4 bytes a pixel, 8 with glass labels) is made when a step first needs it and
//! kept while the budget allows. When the training views do not all fit, the least recently used
//! ones are dropped and uploaded again when their turn comes: the run names the next step's view
//! ([`TargetCache::prefetch`]) so that its upload is queued ahead of that step.
//!
//! The default budget depends on the adapter. On a CPU adapter (lavapipe) "GPU memory" is the
//! same RAM that holds the photos, so keeping every view there would hold each photo twice; a
//! few views are enough to stream from. A GPU keeps a few GiB of photos resident.
use crate::data::View;
use crate::losses::{GpuTarget, LossError};
use trgs_render::GpuContext;

/// Default budget on a CPU adapter (MiB): eight 1600x1200 views.
pub const CPU_ADAPTER_BUDGET_MIB: u64 = 64;
/// Default budget on a GPU (MiB).
pub const GPU_BUDGET_MIB: u64 = 4096;

#[derive(Debug, thiserror::Error)]
pub enum TargetBudgetError {
    #[error(
        "the training views' GPU memory budget ({budget_mib} MiB) cannot hold one view: \
         {name} needs {bytes} bytes; raise --target-memory to at least {need_mib} MiB"
    )]
    TooSmall { budget_mib: u64, name: String, bytes: u64, need_mib: u64 },
}

/// The budget in bytes for the training views on `ctx`'s adapter, `mib` if given.
pub fn budget_bytes(ctx: &GpuContext, mib: Option<u64>) -> u64 {
    let default = match ctx.info.device_type {
        wgpu::DeviceType::Cpu => CPU_ADAPTER_BUDGET_MIB,
        _ => GPU_BUDGET_MIB,
    };
    mib.unwrap_or(default) << 20
}

/// GPU bytes of `view`'s target.
pub fn target_bytes(view: &View) -> u64 {
    bytes_of_target(view.image.width, view.image.height, view.mask.is_some())
}

/// GPU bytes of a target of `width` x `height`: RGBA8, and one u32 label a pixel with a glass
/// mask.
pub fn bytes_of_target(width: u32, height: u32, with_mask: bool) -> u64 {
    u64::from(width) * u64::from(height) * if with_mask { 8 } else { 4 }
}

/// Refuse a budget that cannot hold a target of `bytes` (the view `name`'s).
pub fn check_budget(budget: u64, name: &str, bytes: u64) -> Result<(), TargetBudgetError> {
    if bytes <= budget {
        return Ok(());
    }
    Err(TargetBudgetError::TooSmall {
        budget_mib: budget >> 20,
        name: name.to_string(),
        bytes,
        need_mib: bytes.div_ceil(1 << 20),
    })
}

/// What the cache has done so far (for the tests and the log).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TargetCounts {
    /// Views uploaded (counting every upload again after an eviction).
    pub uploads: u64,
    /// Views dropped to stay under the budget.
    pub evictions: u64,
    /// Uploads made by the step that needed the view (it was not queued ahead with
    /// [`TargetCache::prefetch`]).
    pub uploads_in_step: u64,
    /// Bytes held on the GPU now.
    pub resident_bytes: u64,
}

/// The training views' GPU targets, least recently used dropped first.
#[derive(Debug)]
pub struct TargetCache {
    budget: u64,
    /// Resident targets with their size and the tick of their last use.
    entries: Vec<Entry>,
    tick: u64,
    counts: TargetCounts,
}

#[derive(Debug)]
struct Entry {
    name: String,
    target: GpuTarget,
    bytes: u64,
    used: u64,
}

impl TargetCache {
    pub fn new(budget: u64) -> Self {
        Self { budget, entries: Vec::new(), tick: 0, counts: TargetCounts::default() }
    }

    pub fn budget(&self) -> u64 {
        self.budget
    }

    /// A new budget; targets beyond it are dropped now.
    pub fn set_budget(&mut self, budget: u64) {
        self.budget = budget;
        self.make_room(0);
    }

    pub fn counts(&self) -> TargetCounts {
        self.counts
    }

    /// Queue `view`'s upload ahead of the step that uses it (nothing if it is resident). The
    /// copy runs on the GPU's queue before the next submission; the step that trains on `view`
    /// then finds it resident.
    pub fn prefetch(&mut self, ctx: &GpuContext, view: &View) -> Result<(), TargetError> {
        self.fetch(ctx, view, true).map(|_| ())
    }

    /// `view`'s target, uploaded now if it is not resident.
    pub fn get(&mut self, ctx: &GpuContext, view: &View) -> Result<&GpuTarget, TargetError> {
        self.fetch(ctx, view, false)
    }

    fn fetch(
        &mut self,
        ctx: &GpuContext,
        view: &View,
        ahead: bool,
    ) -> Result<&GpuTarget, TargetError> {
        self.tick += 1;
        let name = &view.camera.name;
        let i = match self.entries.iter().position(|e| &e.name == name) {
            Some(i) => i,
            None => {
                let bytes = target_bytes(view);
                check_budget(self.budget, name, bytes)?;
                self.make_room(bytes);
                let target = GpuTarget::upload(
                    ctx,
                    name,
                    &view.image,
                    view.mask.as_ref(),
                    view.covered.as_ref(),
                )?;
                self.counts.uploads += 1;
                self.counts.uploads_in_step += u64::from(!ahead);
                self.counts.resident_bytes += bytes;
                self.entries.push(Entry { name: name.clone(), target, bytes, used: 0 });
                self.entries.len() - 1
            }
        };
        self.entries[i].used = self.tick;
        Ok(&self.entries[i].target)
    }

    /// Drop least recently used targets until `bytes` more fit the budget.
    fn make_room(&mut self, bytes: u64) {
        while self.counts.resident_bytes + bytes > self.budget {
            let oldest =
                self.entries.iter().enumerate().min_by_key(|(_, e)| e.used).map(|(i, _)| i);
            let Some(oldest) = oldest else { break };
            let e = self.entries.swap_remove(oldest);
            self.counts.resident_bytes -= e.bytes;
            self.counts.evictions += 1;
        }
    }
}

/// Why a view's target could not be made.
#[derive(Debug, thiserror::Error)]
pub enum TargetError {
    #[error(transparent)]
    Budget(#[from] TargetBudgetError),
    #[error(transparent)]
    Loss(#[from] LossError),
}
