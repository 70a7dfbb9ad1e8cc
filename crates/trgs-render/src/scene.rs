//! The scene on the GPU: Gaussians in structure-of-arrays buffers (one buffer per attribute, as
//! `trgs_core::Gaussians` holds them) and the reflection planes. A storage binding may not exceed
//! the adapter's limit (128 MiB on lavapipe), so the per-Gaussian stages bind ranges of these
//! buffers, [`GpuScene::chunks`] Gaussians at a time.
use crate::GpuContext;
use crate::gpu::{self, GpuError};
use trgs_core::scene::{
    Attribute, Gaussians, InvalidInput, PerAttribute, ReflectionPlane, validate_gaussians,
    validate_planes,
};

/// Why [`GpuScene::upload`] failed.
#[derive(Debug, thiserror::Error)]
pub enum UploadError {
    #[error(transparent)]
    Input(#[from] InvalidInput),
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error(
        "{gaussians} Gaussians at SH degree {sh_degree} need a {bytes}-byte buffer of SH \
         coefficients, above this GPU's largest buffer ({limit} bytes): at most {most} \
         Gaussians fit at that degree (in training: a lower --sh-degree, or --densify mcmc \
         with a --cap below it)"
    )]
    TooLarge { gaussians: usize, sh_degree: u32, bytes: u64, limit: u64, most: u64 },
}

/// Gaussians and planes uploaded to a device.
#[derive(Debug)]
pub struct GpuScene {
    len: u32,
    sh_degree: u32,
    sh_coeffs: u32,
    /// One buffer per learnable attribute, laid out as `Gaussians` holds it.
    pub(crate) buffers: PerAttribute<wgpu::Buffer>,
    pub(crate) populations: wgpu::Buffer,
    planes: Vec<ReflectionPlane>,
    chunk: u32,
    /// Gaussians per page of the per-view arrays the rasterize passes bind whole
    /// ([`GpuScene::page_len`]).
    page: u32,
}

/// Bytes per Gaussian of the widest per-Gaussian binding other than SH (the projected record).
const PROJECTED_STRIDE: u64 = std::mem::size_of::<crate::layout::ProjectedGaussian>() as u64;

/// Whole chunks of `chunk` Gaussians whose projected records (the widest per-view record, wider
/// than a gradient record) fit a binding of `limit` bytes; at least one chunk.
fn page_len(limit: u64, chunk: u32) -> u32 {
    let widest = PROJECTED_STRIDE.max(u64::from(crate::layout::PROJECTED_GRAD_FLOATS) * 4);
    let chunks = (limit / widest / u64::from(chunk)).clamp(1, u64::from(u32::MAX / chunk));
    chunks as u32 * chunk
}

/// Whether the widest attribute buffer of `gaussians` (SH) fits a buffer of `limit` bytes: wgpu
/// caps buffers at 2 GiB on most Vulkan drivers, lavapipe's included, whatever the memory.
fn fits_one_buffer(gaussians: &Gaussians<f32>, limit: u64) -> Result<(), UploadError> {
    let per_gaussian = gaussians.sh_coeffs() as u64 * 12;
    let bytes = gaussians.len() as u64 * per_gaussian;
    if bytes <= limit {
        return Ok(());
    }
    Err(UploadError::TooLarge {
        gaussians: gaussians.len(),
        sh_degree: gaussians.sh_degree,
        bytes,
        limit,
        most: limit / per_gaussian,
    })
}

impl GpuScene {
    /// Validate (every attribute finite, no zero quaternion, planes well formed) and upload.
    pub fn upload(
        ctx: &GpuContext,
        gaussians: &Gaussians<f32>,
        planes: &[ReflectionPlane],
    ) -> Result<Self, UploadError> {
        validate_gaussians(gaussians)?;
        validate_planes(planes)?;
        fits_one_buffer(gaussians, ctx.device.limits().max_buffer_size)?;
        // A scene too large for the device's memory fails here, as an error.
        gpu::scoped(ctx, "uploading the Gaussians", || {
            Ok(Self::upload_valid(ctx, gaussians, planes))
        })
    }

    fn upload_valid(
        ctx: &GpuContext,
        gaussians: &Gaussians<f32>,
        planes: &[ReflectionPlane],
    ) -> Self {
        let len = gaussians.len() as u32;
        let flat3 = |v: &[[f32; 3]]| v.iter().flatten().copied().collect::<Vec<f32>>();
        let pops: Vec<u32> = gaussians.populations.iter().map(|&p| p as u32).collect();
        let sh_coeffs = gaussians.sh_coeffs() as u32;
        let limit = ctx.binding_limit();
        let widest = (u64::from(sh_coeffs) * 12).max(PROJECTED_STRIDE);
        // Multiples of 256 Gaussians keep every range offset aligned for any stride; a chunk's
        // one-thread-per-Gaussian dispatches stay within the workgroup limit.
        let most = u64::from(crate::layout::MAX_WORKGROUPS) * 256;
        let chunk = ((limit / widest) / 256 * 256).clamp(256, most) as u32;
        let page = page_len(limit, chunk);
        let g = gaussians;
        let buffers = PerAttribute::from_fn(|a| {
            let label = format!("trgs.scene.{}", a.name());
            match a {
                Attribute::Means => gpu::storage_init(ctx, &label, &flat3(&g.means)),
                Attribute::Rotations => gpu::storage_init(ctx, &label, &g.rotations),
                Attribute::LogScales => gpu::storage_init(ctx, &label, &flat3(&g.log_scales)),
                Attribute::OpacityLogits => gpu::storage_init(ctx, &label, &g.opacity_logits),
                Attribute::Sh => gpu::storage_init(ctx, &label, &flat3(&g.sh)),
                Attribute::MaskLogits => gpu::storage_init(ctx, &label, &g.mask_logits),
                Attribute::LogReflections => gpu::storage_init(ctx, &label, &g.log_reflections),
            }
        });
        Self {
            len,
            sh_degree: gaussians.sh_degree,
            sh_coeffs,
            buffers,
            populations: gpu::storage_init(ctx, "trgs.scene.populations", &pops),
            planes: planes.to_vec(),
            chunk,
            page,
        }
    }

    /// The scene rebuilt with `len` Gaussians: `rebuild(current buffer, words per Gaussian,
    /// label)` makes each new attribute buffer from the current one, every [`Attribute`] and then
    /// the populations (one word each). The planes and binding ranges stay. Densification
    /// gathers rows this way on the GPU. Nothing is validated here, unlike [`GpuScene::upload`]:
    /// rows copied from this scene are as valid as they are now, and whoever writes new values
    /// checks them (the trainer refuses a plan that gives a non-finite one).
    pub fn rebuilt(
        &self,
        len: u32,
        mut rebuild: impl FnMut(&wgpu::Buffer, u32, &str) -> wgpu::Buffer,
    ) -> GpuScene {
        let w = self.attribute_widths();
        let buffers = PerAttribute::from_fn(|a| {
            rebuild(&self.buffers[a], w[a], &format!("trgs.scene.{}", a.name()))
        });
        GpuScene {
            len,
            sh_degree: self.sh_degree,
            sh_coeffs: self.sh_coeffs,
            buffers,
            populations: rebuild(&self.populations, 1, "trgs.scene.populations"),
            planes: self.planes.clone(),
            chunk: self.chunk,
            page: self.page,
        }
    }

    /// Each Gaussian's population, read back.
    pub fn read_populations(
        &self,
        ctx: &GpuContext,
    ) -> Result<Vec<trgs_core::scene::Population>, GpuError> {
        let pops: Vec<u32> = gpu::read_buffer(ctx, &self.populations, 0, self.len as usize)?;
        Ok(pops
            .into_iter()
            .map(|p| trgs_core::scene::Population::from_u8(p as u8).unwrap_or_default())
            .collect())
    }

    pub fn len(&self) -> u32 {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub fn sh_degree(&self) -> u32 {
        self.sh_degree
    }

    /// SH coefficients per colour channel stored per Gaussian.
    pub fn sh_coeffs(&self) -> u32 {
        self.sh_coeffs
    }

    pub fn planes(&self) -> &[ReflectionPlane] {
        &self.planes
    }

    /// Replace the planes (they are a few numbers each and live on the CPU until a render).
    pub fn set_planes(&mut self, planes: &[ReflectionPlane]) -> Result<(), InvalidInput> {
        validate_planes(planes)?;
        self.planes = planes.to_vec();
        Ok(())
    }

    /// Floats per Gaussian of every attribute.
    pub fn attribute_widths(&self) -> PerAttribute<u32> {
        PerAttribute::from_fn(|a| a.width(self.sh_coeffs as usize) as u32)
    }

    /// The buffer of attribute `a` (an optimiser steps it in place).
    pub fn parameter(&self, a: Attribute) -> &wgpu::Buffer {
        &self.buffers[a]
    }

    /// The buffers of every learnable attribute.
    pub fn parameters(&self) -> PerAttribute<&wgpu::Buffer> {
        self.buffers.as_ref()
    }

    /// Each Gaussian's `Population` as a u32 (fixed during training; optimiser-side stages read
    /// it to leave glass Gaussians alone).
    pub fn populations(&self) -> &wgpu::Buffer {
        &self.populations
    }

    /// Read the Gaussians back (after training steps changed them on the GPU).
    pub fn read(&self, ctx: &GpuContext) -> Result<Gaussians<f32>, GpuError> {
        let mut g = read_attributes(ctx, self.parameters(), self.len as usize, self.sh_degree)?;
        g.populations = self.read_populations(ctx)?;
        Ok(g)
    }

    /// Use at most `gaussians` Gaussians per binding (rounded down to a multiple of 256, at
    /// least 256): tests exercise the split that very large scenes need.
    pub fn set_chunk_size(&mut self, gaussians: u32) {
        self.chunk = self.chunk.min((gaussians / 256 * 256).max(256));
        self.page = (self.page / self.chunk).max(1) * self.chunk;
    }

    /// Put at most `gaussians` Gaussians in a page (rounded down to whole chunks, at least one):
    /// tests exercise the pages that scenes of millions of Gaussians need.
    pub fn set_page_len(&mut self, gaussians: u32) {
        self.page = self.page.min((gaussians / self.chunk).max(1) * self.chunk);
    }

    /// Gaussians per page of a view's projected records and their gradients
    /// ([`crate::toolkit::paged`]): as many whole chunks as one binding holds, so that each
    /// chunk's range lies in one page.
    pub fn page_len(&self) -> u32 {
        self.page
    }

    /// (first, count) of each range of Gaussians bound at once.
    pub fn chunks(&self) -> Vec<(u32, u32)> {
        (0..self.len.div_ceil(self.chunk))
            .map(|c| {
                let first = c * self.chunk;
                (first, self.chunk.min(self.len - first))
            })
            .collect()
    }
}

/// Gradients of a [`GpuScene`]'s Gaussians, one buffer per attribute in the scene's own layout
/// (so an optimiser steps each attribute buffer with its gradient buffer).
#[derive(Clone, Debug)]
pub struct SceneGradBuffers {
    buffers: PerAttribute<wgpu::Buffer>,
    len: u32,
    sh_degree: u32,
}

impl SceneGradBuffers {
    /// Zero every gradient (the camera's project_bwd writes only the Gaussians it lists).
    pub(crate) fn clear(&self, encoder: &mut wgpu::CommandEncoder) {
        for b in &self.buffers.0 {
            encoder.clear_buffer(b, 0, None);
        }
    }

    /// Buffers for `scene`'s Gaussians (uninitialised: the backward clears them first).
    pub(crate) fn new(ctx: &GpuContext, pool: &mut gpu::BufferPool, scene: &GpuScene) -> Self {
        let n = u64::from(scene.len);
        let widths = scene.attribute_widths();
        Self {
            buffers: PerAttribute::from_fn(|a| {
                pool.get(ctx, &format!("trgs.grads.{}", a.name()), n * u64::from(widths[a]) * 4)
            }),
            len: scene.len,
            sh_degree: scene.sh_degree,
        }
    }

    /// All-zero gradients for `scene` (for stages that add to gradients, outside a backward).
    pub fn zeros(ctx: &GpuContext, scene: &GpuScene) -> Result<Self, GpuError> {
        gpu::scoped(ctx, "allocating Gaussian gradients", || {
            let g = Self::new(ctx, &mut gpu::BufferPool::default(), scene);
            let mut enc = ctx.device.create_command_encoder(&Default::default());
            g.clear(&mut enc);
            ctx.queue.submit([enc.finish()]);
            Ok(g)
        })
    }

    /// The gradient buffer of attribute `a`.
    pub fn parameter(&self, a: Attribute) -> &wgpu::Buffer {
        &self.buffers[a]
    }

    /// The gradient buffers of every attribute.
    pub fn parameters(&self) -> PerAttribute<&wgpu::Buffer> {
        self.buffers.as_ref()
    }

    /// Read every gradient back, shaped like the scene's Gaussians (populations are not
    /// parameters and read as Primary).
    pub fn read(&self, ctx: &GpuContext) -> Result<Gaussians<f32>, GpuError> {
        read_attributes(ctx, self.parameters(), self.len as usize, self.sh_degree)
    }
}

/// Every attribute buffer of `n` Gaussians read back; populations are left Primary.
fn read_attributes(
    ctx: &GpuContext,
    b: PerAttribute<&wgpu::Buffer>,
    n: usize,
    sh_degree: u32,
) -> Result<Gaussians<f32>, GpuError> {
    let mut g = Gaussians::<f32>::zeros(n, sh_degree);
    let coeffs = g.sh_coeffs();
    g.means = gpu::read_buffer(ctx, b[Attribute::Means], 0, n)?;
    g.rotations = gpu::read_buffer(ctx, b[Attribute::Rotations], 0, n)?;
    g.log_scales = gpu::read_buffer(ctx, b[Attribute::LogScales], 0, n)?;
    g.opacity_logits = gpu::read_buffer(ctx, b[Attribute::OpacityLogits], 0, n)?;
    g.sh = gpu::read_buffer(ctx, b[Attribute::Sh], 0, n * coeffs)?;
    g.mask_logits = gpu::read_buffer(ctx, b[Attribute::MaskLogits], 0, n)?;
    g.log_reflections = gpu::read_buffer(ctx, b[Attribute::LogReflections], 0, n)?;
    Ok(g)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scene_whose_sh_outgrows_one_buffer_is_refused_with_the_count_that_fits() {
        let g = Gaussians::<f32>::zeros(1000, 3); // 192 bytes of SH each
        assert!(fits_one_buffer(&g, 192_000).is_ok());
        let err = fits_one_buffer(&g, 191_999).expect_err("one byte short").to_string();
        assert!(
            err.contains("1000 Gaussians at SH degree 3") && err.contains("at most 999"),
            "{err}"
        );
    }
}
