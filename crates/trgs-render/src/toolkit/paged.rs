//! Arrays larger than one storage binding, held as pages.
//!
//! The rasterize passes and their adjoints read a view's projected Gaussians (and add to their
//! gradient records) at any Gaussian index the sorted keys name, so they bind those arrays
//! whole. At 64 bytes a record, a binding of 128 MiB (lavapipe's limit) holds about 2.1 million
//! Gaussians. Such an array is therefore split into pages of [`Paged::page_len`] Gaussians, each
//! page its own buffer: the rasterize kernels bind [`MAX_PAGES`] of them and pick the page by
//! the index (their `_paged` variants: `shaders/shared/raster_pages.wgsl`, `PAGED` in
//! `shaders/shared/accumulate.wgsl`; a frame of one page runs the kernels without the choice);
//! the per-Gaussian stages run over the scene's chunks, and a page holds a whole number of
//! chunks ([`crate::GpuScene::page_len`]), so a chunk's range lies in one page.
//!
//! The frame's tile keys are paged the same way ([`crate::stages::sort::KeyList`]): the key
//! list is bound whole by `emit_keys`, `sort`, `tile_ranges` and the rasterize passes, and at 4
//! bytes a key one binding of 128 MiB holds 33.5 million keys
//! (`shaders/shared/key_pages.wgsl`).
use super::gpu::{self, BufferPool};
use crate::GpuContext;
use crate::gpu::GpuError;

/// Pages the rasterize kernels bind (their bindings `projected` and `projected_hi`, `grads` and
/// `grads_hi`).
pub const MAX_PAGES: u32 = 2;

/// A per-Gaussian array of `len` records of `stride` bytes in pages of `page_len` records.
#[derive(Clone, Debug)]
pub struct Paged {
    pages: Vec<wgpu::Buffer>,
    page_len: u32,
    len: u32,
    stride: u64,
}

impl Paged {
    /// The pages of `len` records from `pool`, labelled `{label}.p{k}` (reused frame to frame).
    pub fn from_pool(
        ctx: &GpuContext,
        pool: &mut BufferPool,
        label: &str,
        len: u32,
        page_len: u32,
        stride: u64,
    ) -> Self {
        let page_len = page_len.max(1);
        let count = len.div_ceil(page_len).max(1);
        let mut paged = Self { pages: Vec::new(), page_len, len, stride };
        paged.pages = (0..count)
            .map(|k| {
                let bytes = u64::from(paged.records_in(k).max(1)) * stride;
                pool.get(ctx, &format!("{label}.p{k}"), bytes)
            })
            .collect();
        paged
    }

    /// Records held by page `k`.
    fn records_in(&self, k: u32) -> u32 {
        self.page_len.min(self.len.saturating_sub(k * self.page_len))
    }

    /// Records in the first page (what the kernels' `page` parameter holds): records from this
    /// index on are in the second page.
    pub fn first_page_len(&self) -> u32 {
        self.page_len.min(self.len)
    }

    pub fn page_len(&self) -> u32 {
        self.page_len
    }

    pub fn pages(&self) -> &[wgpu::Buffer] {
        &self.pages
    }

    /// Whether there is a second page (the rasterize kernels' `_paged` variants then run).
    pub fn is_paged(&self) -> bool {
        self.pages.len() > 1
    }

    /// Records `first..first + count` as one binding (they must lie in one page: the scene's
    /// chunks do).
    pub fn range(&self, first: u32, count: u32) -> wgpu::BindingResource<'_> {
        let (page, local) = (first / self.page_len, first % self.page_len);
        debug_assert!(
            local + count <= self.page_len,
            "records {first}..{} cross a page of {}",
            first + count,
            self.page_len
        );
        gpu::range(
            &self.pages[page as usize],
            u64::from(local) * self.stride,
            u64::from(count) * self.stride,
        )
    }

    /// The first page whole as a binding.
    pub fn first_page(&self) -> wgpu::BindingResource<'_> {
        self.pages[0].as_entire_binding()
    }

    /// The second page whole as a binding, if there is one (the `_paged` kernels bind it last).
    pub fn second_page(&self) -> Option<wgpu::BindingResource<'_>> {
        self.pages.get(1).map(wgpu::Buffer::as_entire_binding)
    }

    /// The second page, or the first again where there is none: for a read-only binding of a
    /// `_paged` kernel that runs for another array's second page (`page` then equals the
    /// length, so the kernel never reads it).
    pub fn second_page_or_first(&self) -> wgpu::BindingResource<'_> {
        self.second_page().unwrap_or_else(|| self.first_page())
    }

    /// Zero every page.
    pub fn clear(&self, encoder: &mut wgpu::CommandEncoder) {
        for p in &self.pages {
            encoder.clear_buffer(p, 0, None);
        }
    }

    /// Every record, in order (blocking readback of each page).
    pub fn read<T: bytemuck::Pod>(&self, ctx: &GpuContext) -> Result<Vec<T>, GpuError> {
        self.read_range(ctx, 0, self.len)
    }

    /// Records `first..first + count`, in order, across pages (blocking readback).
    pub fn read_range<T: bytemuck::Pod>(
        &self,
        ctx: &GpuContext,
        first: u32,
        count: u32,
    ) -> Result<Vec<T>, GpuError> {
        let per_record = (self.stride as usize) / std::mem::size_of::<T>();
        let end = (first + count).min(self.len);
        let mut out = Vec::with_capacity(end.saturating_sub(first) as usize * per_record);
        for (k, p) in self.pages.iter().enumerate() {
            let start = k as u32 * self.page_len;
            let (lo, hi) = (first.max(start), end.min(start + self.records_in(k as u32)));
            if lo < hi {
                let offset = u64::from(lo - start) * self.stride;
                out.extend(gpu::read_buffer::<T>(ctx, p, offset, (hi - lo) as usize * per_record)?);
            }
        }
        Ok(out)
    }
}
