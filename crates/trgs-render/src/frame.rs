//! A rendered view on the GPU: every layer, what the backward pass will need (projected
//! Gaussians, sorted lists, per-pixel states), and readback to images.
use crate::GpuContext;
use crate::gpu::{self, BufferPool, GpuError, KernelTime};
use crate::layout::{ProjectParams, RasterState, ReflectionState};
use crate::stages::sort::KeyList;
use crate::toolkit::paged::Paged;
use trgs_core::Image;
use trgs_core::pipeline::{TileGrid, TileRect};
use trgs_core::scene::ViewTransform;

mod intermediates;
pub(crate) mod key_totals;
mod stage_reads;
pub use intermediates::{DepthOrderIntermediates, ViewIntermediates};
pub use key_totals::{KeySizing, KeyTotals, PendingKeyTotals};

/// The geometry stages of one view (the real camera is view 0, then one per mirrored pass).
#[derive(Debug)]
pub struct ViewBuffers {
    pub view: ViewTransform,
    /// The plane this view is mirrored about.
    pub plane: Option<usize>,
    /// The tiles binned (a plane's footprint, or the whole grid).
    pub limit: TileRect,
    /// The parameter block `project` ran with (its adjoint recomputes from the same view).
    pub(crate) project_params: ProjectParams,
    pub projected: Paged,
    /// The Gaussians that passed project's cheap culls (project_bwd runs over them only).
    pub(crate) candidates: crate::stages::project::Candidates,
    /// The tiles each Gaussian touches (zero for the culled).
    pub counts: wgpu::Buffer,
    /// The sorted keys (tile indices) and values (Gaussian indices) of every view of the frame
    /// (one list, sorted once): this view's are the `num_keys` from `key_base`.
    pub keys: Option<KeyList>,
    /// (start, end) per sorted tile index, every view's (shared): this view's tiles are numbered
    /// from `tile_base`, row by row within `limit`.
    pub ranges: Option<wgpu::Buffer>,
    pub num_keys: u32,
    pub key_base: u32,
    pub tile_base: u32,
}

/// The frame's depth order and key emission, every view's together.
#[derive(Debug)]
pub(crate) struct Binning {
    /// The depth order (keys: depth bits, values: entry indices `view * Gaussians + index`).
    pub order: KeyList,
    /// The exclusive scan of the tile counts in depth order (each entry's first key slot).
    pub offsets: wgpu::Buffer,
    pub entries: u32,
    /// Keys of all views.
    pub total: u32,
    /// The keys as emitted, before the sort (with `capture_intermediates`).
    pub emitted: Option<KeyList>,
    /// emit_keys' two words: the keys the list held, and whether it dropped some.
    pub kept: wgpu::Buffer,
}

impl ViewBuffers {
    /// The whole grid's index of this view's sorted tile index `tile`.
    fn grid_tile(&self, grid: &TileGrid, tile: u32) -> u32 {
        let local = tile - self.tile_base;
        let w = self.limit.x1 - self.limit.x0;
        (self.limit.y0 + local / w) * grid.tiles_x + self.limit.x0 + local % w
    }
}

/// Per-pixel layer buffers.
#[derive(Clone, Debug)]
pub struct LayerBuffers {
    /// (C_t, 1 - T_t)
    pub transmission: wgpu::Buffer,
    /// (D_t, V, M, 0)
    pub geometry: wgpu::Buffer,
    pub states: wgpu::Buffer,
    /// (C_raw^k, A^k) per plane slot.
    pub reflection_raw: wgpu::Buffer,
    pub reflection_states: wgpu::Buffer,
    /// (C, 1 - T_t): compose keeps the transmission layer's alpha, which the renderer copies
    /// outside compose's area.
    pub color: wgpu::Buffer,
    /// (C_r, 0)
    pub reflection: wgpu::Buffer,
    /// (R_raw, R, 0, 0)
    pub strength: wgpu::Buffer,
    pub hit: wgpu::Buffer,
}

/// One rendered view. Buffers are reused when the frame is rendered into again.
#[derive(Debug, Default)]
pub struct Frame {
    pub(crate) pool: BufferPool,
    grid: Option<TileGrid>,
    plane_count: usize,
    gaussian_count: u32,
    depth_variance: bool,
    background: [f32; 3],
    layers: Option<LayerBuffers>,
    /// The camera rays and planes compose read (kept for compose_bwd).
    rays: Option<crate::stages::compose::RayBuffers>,
    views: Vec<ViewBuffers>,
    binning: Option<Binning>,
    has_pass: Vec<bool>,
    stage_times: Option<Vec<(&'static str, f64)>>,
    kernel_times: Option<Vec<KernelTime>>,
    /// The last render's key totals, once known ([`Frame::settle_keys`]).
    key_totals: Option<KeyTotals>,
    /// Their readback, when the render did not wait for it.
    pending_keys: Option<key_totals::PendingKeyTotals>,
    /// The most keys any render into this frame had (sizes lists from earlier frames).
    largest_keys: u64,
    /// The keys expected of the next render, after its set changed size, and the render after
    /// which that was said ([`Frame::expect_set_scaled`]): until a render of the new set reports
    /// its totals.
    expected_keys: Option<(u64, u64)>,
    /// Renders into this frame so far (which render a readback of key totals belongs to).
    renders: u64,
}

/// A layer of a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layer {
    /// C, RGB.
    Color,
    /// C_t, RGB.
    Transmission,
    /// C_r = C_raw A of the hit plane, RGB.
    Reflection,
    /// R = H R_raw M.
    Strength,
    /// R_raw (Schlick; zero without a hit).
    StrengthRaw,
    /// M.
    Mask,
    /// D_t.
    Depth,
    /// V (zero unless rendered with `depth_variance`).
    DepthVariance,
    /// 1 - T_t.
    Alpha,
}

impl Layer {
    pub const ALL: [Layer; 9] = [
        Layer::Color,
        Layer::Transmission,
        Layer::Reflection,
        Layer::Strength,
        Layer::StrengthRaw,
        Layer::Mask,
        Layer::Depth,
        Layer::DepthVariance,
        Layer::Alpha,
    ];

    /// Lower-case name used in file names.
    pub fn name(self) -> &'static str {
        match self {
            Layer::Color => "color",
            Layer::Transmission => "transmission",
            Layer::Reflection => "reflection",
            Layer::Strength => "strength",
            Layer::StrengthRaw => "strength_raw",
            Layer::Mask => "mask",
            Layer::Depth => "depth",
            Layer::DepthVariance => "depth_variance",
            Layer::Alpha => "alpha",
        }
    }

    pub fn channels(self) -> u32 {
        match self {
            Layer::Color | Layer::Transmission | Layer::Reflection => 3,
            _ => 1,
        }
    }
}

/// Every layer read back, as the CPU twin's `Frame` holds them.
#[derive(Clone, Debug)]
pub struct FrameImages {
    pub color: Image<f32>,
    pub transmission: Image<f32>,
    pub depth: Image<f32>,
    pub depth_variance: Image<f32>,
    pub mask: Image<f32>,
    pub alpha: Image<f32>,
    pub hit: Image<u32>,
    pub strength_raw: Image<f32>,
    pub strength: Image<f32>,
    pub reflection: Image<f32>,
    /// Per plane: (C_raw, A, footprint), None where the mirrored pass did not run.
    pub planes: Vec<Option<PlaneImages>>,
}

#[derive(Clone, Debug)]
pub struct PlaneImages {
    pub raw_color: Image<f32>,
    pub intensity: Image<f32>,
    pub footprint: TileRect,
}

impl Frame {
    pub(crate) fn reset(
        &mut self,
        grid: TileGrid,
        plane_count: usize,
        gaussian_count: u32,
        depth_variance: bool,
        background: [f32; 3],
    ) {
        self.grid = Some(grid);
        self.plane_count = plane_count;
        self.gaussian_count = gaussian_count;
        self.depth_variance = depth_variance;
        self.background = background;
        self.views.clear();
        self.binning = None;
        self.stage_times = None;
        self.kernel_times = None;
        self.key_totals = None;
        self.pending_keys = None;
        self.renders += 1;
        // Until this render finishes the frame holds no image: a render that fails part way
        // leaves it "not rendered" (empty reads, BackwardError::NotRendered), never the previous
        // frame's buffers read with this frame's size.
        self.layers = None;
        self.rays = None;
        self.has_pass.clear();
    }

    pub(crate) fn layers(&mut self, ctx: &GpuContext, pixels: u64) -> LayerBuffers {
        let slots = self.plane_count.max(1) as u64;
        let p = &mut self.pool;
        let state = std::mem::size_of::<RasterState>() as u64;
        let rstate = std::mem::size_of::<ReflectionState>() as u64;
        let l = LayerBuffers {
            transmission: p.get(ctx, "trgs.rasterize.transmission", pixels * 16),
            geometry: p.get(ctx, "trgs.rasterize.geometry", pixels * 16),
            states: p.get(ctx, "trgs.rasterize.states", pixels * state),
            reflection_raw: p.get(ctx, "trgs.rasterize_reflection.raw", slots * pixels * 16),
            reflection_states: p.get(
                ctx,
                "trgs.rasterize_reflection.states",
                slots * pixels * rstate,
            ),
            color: p.get(ctx, "trgs.compose.color", pixels * 16),
            reflection: p.get(ctx, "trgs.compose.reflection", pixels * 16),
            strength: p.get(ctx, "trgs.compose.strength", pixels * 16),
            hit: p.get(ctx, "trgs.compose.hit", pixels * 4),
        };
        self.layers = Some(l.clone());
        l
    }

    pub(crate) fn finish(
        &mut self,
        views: Vec<ViewBuffers>,
        binning: Binning,
        has_pass: Vec<bool>,
        rays: Option<crate::stages::compose::RayBuffers>,
        rec: &gpu::Recorder,
    ) {
        self.views = views;
        self.binning = Some(binning);
        self.rays = rays;
        self.has_pass = has_pass;
        self.stage_times = rec.stage_times();
        self.kernel_times = rec.kernel_times();
    }

    pub(crate) fn rays(&self) -> Option<&crate::stages::compose::RayBuffers> {
        self.rays.as_ref()
    }

    pub(crate) fn grid(&self) -> Option<TileGrid> {
        self.grid
    }

    /// Number of Gaussians of the scene this frame was rendered from.
    pub fn gaussian_count(&self) -> u32 {
        self.gaussian_count
    }

    /// Whether the frame has the depth-variance layer.
    pub fn has_depth_variance(&self) -> bool {
        self.depth_variance
    }

    pub(crate) fn background(&self) -> [f32; 3] {
        self.background
    }

    /// Number of planes of the scene this frame was rendered from.
    pub fn plane_count(&self) -> usize {
        self.plane_count
    }

    /// Number of plane slots in the per-plane layers (at least 1).
    pub fn plane_slots(&self) -> usize {
        self.plane_count.max(1)
    }

    pub fn width(&self) -> u32 {
        self.grid.map_or(0, |g| g.width)
    }

    pub fn height(&self) -> u32 {
        self.grid.map_or(0, |g| g.height)
    }

    /// Whether any mirrored pass ran (otherwise C = C_t and the reflection layers are zero).
    pub fn composed(&self) -> bool {
        self.has_pass.iter().any(|&p| p)
    }

    /// Whether plane k's mirrored pass ran.
    pub fn plane_rendered(&self, k: usize) -> bool {
        self.has_pass.get(k).copied().unwrap_or(false)
    }

    /// Milliseconds per stage, when rendered with `profile` on an adapter with timestamps.
    pub fn stage_times(&self) -> Option<&[(&'static str, f64)]> {
        self.stage_times.as_deref()
    }

    /// The stage times split by kernel, when rendered with `profile`.
    pub fn kernel_times(&self) -> Option<&[KernelTime]> {
        self.kernel_times.as_deref()
    }

    /// Renders into this frame so far.
    pub(crate) fn renders(&self) -> u64 {
        self.renders
    }

    /// Total keys sorted over all views (of a list sized from earlier frames: once settled,
    /// [`Frame::settle_keys`]).
    pub fn key_count(&self) -> u64 {
        self.views.iter().map(|v| u64::from(v.num_keys)).sum()
    }

    /// GPU memory held by this frame's buffers, in bytes.
    pub fn memory_bytes(&self) -> u64 {
        self.pool.bytes()
    }

    fn pixels(&self) -> usize {
        (self.width() * self.height()) as usize
    }

    fn read_vec4(
        &self,
        ctx: &GpuContext,
        buffer: &wgpu::Buffer,
        offset_pixels: usize,
    ) -> Result<Vec<[f32; 4]>, GpuError> {
        gpu::read_buffer(ctx, buffer, offset_pixels as u64 * 16, self.pixels())
    }

    fn channel_image(&self, data: &[[f32; 4]], channels: std::ops::Range<usize>) -> Image<f32> {
        let mut img = Image::new(self.width(), self.height(), channels.len() as u32);
        for (p, v) in data.iter().enumerate() {
            for (c, ch) in channels.clone().enumerate() {
                img.data[p * channels.len() + c] = v[ch];
            }
        }
        img
    }

    /// Where `layer` lives: its buffer (one vec4 per pixel) and the components that hold it.
    /// None when the frame does not have it (not rendered, or a reflection layer of a frame
    /// that was not composed because no plane was in view).
    pub fn layer_source(&self, layer: Layer) -> Option<(&wgpu::Buffer, std::ops::Range<usize>)> {
        let l = self.layers.as_ref()?;
        let composed = self.composed();
        Some(match layer {
            Layer::Color if composed => (&l.color, 0..3),
            Layer::Color | Layer::Transmission => (&l.transmission, 0..3),
            Layer::Alpha => (&l.transmission, 3..4),
            Layer::Depth => (&l.geometry, 0..1),
            Layer::DepthVariance => (&l.geometry, 1..2),
            Layer::Mask => (&l.geometry, 2..3),
            _ if !composed => return None,
            Layer::Reflection => (&l.reflection, 0..3),
            Layer::StrengthRaw => (&l.strength, 0..1),
            Layer::Strength => (&l.strength, 1..2),
        })
    }

    /// Read one layer back (zeros for a layer the frame does not have).
    pub fn read_layer(&self, ctx: &GpuContext, layer: Layer) -> Result<Image<f32>, GpuError> {
        if self.layers.is_none() {
            return Ok(Image::new(0, 0, layer.channels()));
        }
        Ok(match self.layer_source(layer) {
            Some((buffer, range)) => self.channel_image(&self.read_vec4(ctx, buffer, 0)?, range),
            None => Image::new(self.width(), self.height(), layer.channels()),
        })
    }

    /// Read every layer back (each layer buffer once).
    pub fn read_images(&self, ctx: &GpuContext) -> Result<FrameImages, GpuError> {
        let (w, h) = (self.width(), self.height());
        let Some(l) = &self.layers else {
            let z = |c| Image::new(w, h, c);
            return Ok(FrameImages {
                color: z(3),
                transmission: z(3),
                depth: z(1),
                depth_variance: z(1),
                mask: z(1),
                alpha: z(1),
                hit: Image::new(w, h, 1),
                strength_raw: z(1),
                strength: z(1),
                reflection: z(3),
                planes: Vec::new(),
            });
        };
        let transmission = self.read_vec4(ctx, &l.transmission, 0)?;
        let geometry = self.read_vec4(ctx, &l.geometry, 0)?;
        let composed = self.composed();
        let (color, reflection, strength, hit) = if composed {
            (
                self.channel_image(&self.read_vec4(ctx, &l.color, 0)?, 0..3),
                self.channel_image(&self.read_vec4(ctx, &l.reflection, 0)?, 0..3),
                self.read_vec4(ctx, &l.strength, 0)?,
                Image {
                    width: w,
                    height: h,
                    channels: 1,
                    data: gpu::read_buffer(ctx, &l.hit, 0, self.pixels())?,
                },
            )
        } else {
            (
                self.channel_image(&transmission, 0..3),
                Image::new(w, h, 3),
                vec![[0.0; 4]; self.pixels()],
                Image::new(w, h, 1),
            )
        };
        let mut planes = Vec::with_capacity(self.plane_count);
        for k in 0..self.plane_count {
            let Some(v) = self.views.iter().find(|v| v.plane == Some(k)) else {
                planes.push(None);
                continue;
            };
            let raw = self.read_vec4(ctx, &l.reflection_raw, k * self.pixels())?;
            planes.push(Some(PlaneImages {
                raw_color: self.channel_image(&raw, 0..3),
                intensity: self.channel_image(&raw, 3..4),
                footprint: v.limit,
            }));
        }
        Ok(FrameImages {
            color,
            transmission: self.channel_image(&transmission, 0..3),
            depth: self.channel_image(&geometry, 0..1),
            depth_variance: self.channel_image(&geometry, 1..2),
            mask: self.channel_image(&geometry, 2..3),
            alpha: self.channel_image(&transmission, 3..4),
            hit,
            strength_raw: self.channel_image(&strength, 0..1),
            strength: self.channel_image(&strength, 1..2),
            reflection,
            planes,
        })
    }
}

/// The backward pass's working buffers, from the frame's pool (reused from step to step).
#[derive(Debug)]
pub(crate) struct BackwardBuffers {
    /// Per view: PROJECTED_GRAD_FLOATS per Gaussian.
    pub projected_grads: Vec<Paged>,
    /// VIEW_GRAD_FLOATS per view at `view_stride` bytes (a binding offset must be aligned).
    pub view_grads: wgpu::Buffer,
    pub view_stride: u64,
    /// PLANE_GRAD_FLOATS per plane (compose_bwd's sums).
    pub plane_grads: wgpu::Buffer,
    pub scene_grads: crate::scene::SceneGradBuffers,
}

impl Frame {
    pub(crate) fn backward_buffers(
        &mut self,
        ctx: &GpuContext,
        scene: &crate::GpuScene,
    ) -> BackwardBuffers {
        use crate::layout::{PLANE_GRAD_FLOATS, PROJECTED_GRAD_FLOATS, VIEW_GRAD_FLOATS};
        let n = self.gaussian_count;
        let views = self.views.len().max(1) as u64;
        let align = u64::from(ctx.device.limits().min_storage_buffer_offset_alignment);
        let view_stride = (u64::from(VIEW_GRAD_FLOATS) * 4).div_ceil(align) * align;
        let planes = self.plane_count.max(1) as u64;
        let pool = &mut self.pool;
        BackwardBuffers {
            projected_grads: (0..self.views.len())
                .map(|vi| {
                    let label = format!("trgs.rasterize_bwd.projected_grads.v{vi}");
                    let stride = u64::from(PROJECTED_GRAD_FLOATS) * 4;
                    Paged::from_pool(ctx, pool, &label, n, scene.page_len(), stride)
                })
                .collect(),
            view_grads: pool.get(ctx, "trgs.project_bwd.view_grads", views * view_stride),
            view_stride,
            plane_grads: pool.get(
                ctx,
                "trgs.compose_bwd.plane_grads",
                planes * PLANE_GRAD_FLOATS * 4,
            ),
            scene_grads: crate::scene::SceneGradBuffers::new(ctx, pool, scene),
        }
    }
}
