//! A frame's layer as 8-bit RGBA on the GPU, for a window (a texture the UI samples, with no trip
//! through the CPU) or for a PNG ([`DisplayTarget::read_rgba`]). Stage `display` does the
//! conversion; this module picks the buffer and mapping of each [`Layer`] and owns the target.
use crate::gpu::{self, GpuError, Recorder};
use crate::stages::{self, Stage};
use crate::toolkit::FrameStages;
use crate::{Frame, GpuContext, Layer, Renderer};
use trgs_core::Image;
use trgs_core::pipeline::DisplayMapping;

/// Texture rows must start every 256 bytes in a buffer-to-texture copy.
const ROW_ALIGN_PIXELS: u32 = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT / 4;

/// A display image on the GPU: the packed pixels (rows padded to 256 bytes) and an `Rgba8Unorm`
/// texture holding the same values, ready to be sampled by a UI.
#[derive(Debug)]
pub struct DisplayTarget {
    width: u32,
    height: u32,
    row_pixels: u32,
    rgba: wgpu::Buffer,
    texture: wgpu::Texture,
    view: wgpu::TextureView,
}

/// Why a frame could not be displayed.
#[derive(Debug, thiserror::Error)]
pub enum DisplayError {
    #[error("display target is {target:?} but the frame is {frame:?}")]
    SizeMismatch { target: (u32, u32), frame: (u32, u32) },
    #[error("the frame has not been rendered")]
    NotRendered,
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

impl DisplayTarget {
    /// A target of `width x height` (each at least 1).
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Result<Self, GpuError> {
        gpu::scoped(ctx, "allocating a display target", || Ok(Self::allocate(ctx, width, height)))
    }

    fn allocate(ctx: &GpuContext, width: u32, height: u32) -> Self {
        let (width, height) = (width.max(1), height.max(1));
        let row_pixels = width.div_ceil(ROW_ALIGN_PIXELS) * ROW_ALIGN_PIXELS;
        let rgba = gpu::storage(ctx, "trgs.display.rgba", u64::from(row_pixels * height) * 4);
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("trgs.display.texture"),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8Unorm,
            usage: wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_DST
                | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        Self { width, height, row_pixels, rgba, texture, view }
    }

    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    pub fn texture(&self) -> &wgpu::Texture {
        &self.texture
    }

    pub fn texture_view(&self) -> &wgpu::TextureView {
        &self.view
    }

    /// The last displayed image as RGBA bytes (4 channels, row-major, no padding).
    pub fn read_rgba(&self, ctx: &GpuContext) -> Result<Image<u8>, GpuError> {
        let words: Vec<u32> =
            gpu::read_buffer(ctx, &self.rgba, 0, (self.row_pixels * self.height) as usize)?;
        let mut img = Image::new(self.width, self.height, 4);
        for y in 0..self.height as usize {
            let row = &words[y * self.row_pixels as usize..][..self.width as usize];
            for (x, w) in row.iter().enumerate() {
                let at = (y * self.width as usize + x) * 4;
                img.data[at..at + 4].copy_from_slice(&w.to_le_bytes());
            }
        }
        Ok(img)
    }
}

/// The layer buffer `layer` is read from ([`Frame::layer_source`]) and how its values map to
/// colours; a layer the frame does not have shows black. `depth_range` is the (near, far) of the
/// inverse-depth display of [`Layer::Depth`]. None before the frame is rendered.
pub fn layer_mapping(
    frame: &Frame,
    layer: Layer,
    depth_range: [f32; 2],
) -> Option<(&wgpu::Buffer, DisplayMapping)> {
    let l = frame.layer_buffers()?;
    let Some((buffer, range)) = frame.layer_source(layer) else {
        return Some((&l.transmission, DisplayMapping::Black));
    };
    let channel = range.start as u32;
    let mapping = match layer {
        _ if range.len() == 3 => DisplayMapping::Rgb,
        Layer::Depth => {
            let [near, far] = depth_range;
            DisplayMapping::InverseDepth { channel, near, far }
        }
        _ => DisplayMapping::Gray { channel },
    };
    Some((buffer, mapping))
}

impl Renderer {
    /// Convert `layer` of `frame` into `target` (its packed buffer and its texture) and wait.
    pub fn display(
        &self,
        frame: &Frame,
        layer: Layer,
        depth_range: [f32; 2],
        target: &DisplayTarget,
    ) -> Result<(), DisplayError> {
        let size = (frame.width(), frame.height());
        if size != target.size() {
            return Err(DisplayError::SizeMismatch { target: target.size(), frame: size });
        }
        let (buffer, mapping) =
            layer_mapping(frame, layer, depth_range).ok_or(DisplayError::NotRendered)?;
        let ctx = &self.ctx;
        let scopes = gpu::ErrorScopes::open(ctx, "converting a layer for display");
        let s = Stage { ctx, kernels: &self.kernels };
        let mut rec = Recorder::new(ctx, "trgs.display", false);
        let dims = (target.width, target.height, target.row_pixels);
        stages::display::record(s, &mut rec, dims, mapping, buffer, &target.rgba);
        rec.encoder.copy_buffer_to_texture(
            wgpu::TexelCopyBufferInfo {
                buffer: &target.rgba,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(target.row_pixels * 4),
                    rows_per_image: Some(target.height),
                },
            },
            wgpu::TexelCopyTextureInfo {
                texture: &target.texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::Extent3d { width: target.width, height: target.height, depth_or_array_layers: 1 },
        );
        let waited = rec.submit_and_wait(ctx);
        scopes.close_after(waited.map_err(DisplayError::from))
    }
}
