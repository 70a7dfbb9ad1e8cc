//! dL/d(each layer of a frame) on the GPU: the input of the backward pass. Shaped like the
//! frame's own layer buffers ([`crate::LayerBuffers`]), so a loss kernel writes each gradient
//! where the forward wrote the value. The backward consumes them: compose_bwd adds its terms into
//! the pass-layer gradients in place.
use crate::frame::Frame;
use crate::{GpuContext, GpuError, gpu};
use trgs_core::Image;
use trgs_core::reference::FrameGrads;

/// Gradient buffers shaped like the forward layers they belong to.
#[derive(Clone, Debug)]
pub struct LayerGrads {
    /// dL/d(C, -), read.
    pub color: wgpu::Buffer,
    /// dL/d(C_r, -), read.
    pub reflection: wgpu::Buffer,
    /// dL/d(R_raw, R, -, -), read.
    pub strength: wgpu::Buffer,
    /// dL/d(C_t, alpha): direct in, total out.
    pub transmission: wgpu::Buffer,
    /// dL/d(D_t, V, M, -): direct in, total out.
    pub geometry: wgpu::Buffer,
    /// dL/d(C_raw^k, A^k) per plane slot: direct in, total out.
    pub reflection_raw: wgpu::Buffer,
    /// The image size (width, height) of the frame they were made for: gradients of a frame with
    /// as many pixels in another shape fit the buffers but would be read at the wrong pixels.
    pub size: (u32, u32),
}

#[derive(Debug, thiserror::Error)]
pub enum LayerGradsError {
    #[error(
        "gradient of layer {layer}: {got_w}x{got_h}x{got_c}, the frame needs {want_w}x{want_h}x{want_c}"
    )]
    Shape {
        layer: &'static str,
        got_w: u32,
        got_h: u32,
        got_c: u32,
        want_w: u32,
        want_h: u32,
        want_c: u32,
    },
    #[error("gradient of layer {layer}: {got} planes, the frame has {want}")]
    Planes { layer: &'static str, got: usize, want: usize },
    #[error("gradient of layer {layer} at pixel ({x}, {y}) is not finite ({value})")]
    NonFinite { layer: &'static str, x: u32, y: u32, value: f64 },
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

/// Pack up to four channels of several images per pixel, after checking shape and finiteness.
fn pack(
    w: u32,
    h: u32,
    parts: &[(&'static str, &Image<f64>, u32, usize)],
) -> Result<Vec<[f32; 4]>, LayerGradsError> {
    let mut out = vec![[0.0f32; 4]; (w * h) as usize];
    for &(layer, im, channels, first) in parts {
        if (im.width, im.height, im.channels) != (w, h, channels) {
            return Err(LayerGradsError::Shape {
                layer,
                got_w: im.width,
                got_h: im.height,
                got_c: im.channels,
                want_w: w,
                want_h: h,
                want_c: channels,
            });
        }
        for (i, &v) in im.data.iter().enumerate() {
            let pixel = i / channels as usize;
            if !v.is_finite() {
                let (x, y) = (pixel as u32 % w, pixel as u32 / w);
                return Err(LayerGradsError::NonFinite { layer, x, y, value: v });
            }
            out[pixel][first + i % channels as usize] = v as f32;
        }
    }
    Ok(out)
}

impl LayerGrads {
    /// The first buffer too small for `frame` (layer name, bytes held, bytes needed): gradients
    /// made for a smaller frame would be read out of range.
    pub(crate) fn too_small_for(&self, frame: &Frame) -> Option<(&'static str, u64, u64)> {
        let pixels = u64::from(frame.width()) * u64::from(frame.height());
        let slots = frame.plane_slots() as u64;
        [
            ("color", &self.color, pixels * 16),
            ("reflection", &self.reflection, pixels * 16),
            ("strength", &self.strength, pixels * 16),
            ("transmission", &self.transmission, pixels * 16),
            ("geometry", &self.geometry, pixels * 16),
            ("reflection_raw", &self.reflection_raw, slots * pixels * 16),
        ]
        .into_iter()
        .find(|(_, b, need)| b.size() < *need)
        .map(|(name, b, need)| (name, b.size(), need))
    }

    /// All-zero gradients for `frame` (a loss kernel then writes the layers it depends on).
    pub fn zeros(ctx: &GpuContext, frame: &Frame) -> Result<Self, GpuError> {
        gpu::scoped(ctx, "allocating layer gradients", || Ok(Self::zeroed(ctx, frame)))
    }

    fn zeroed(ctx: &GpuContext, frame: &Frame) -> Self {
        let pixels = u64::from(frame.width()) * u64::from(frame.height());
        let slots = frame.plane_slots() as u64;
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        let mut zeroed = |name: &str, bytes: u64| {
            let b = gpu::storage(ctx, &format!("trgs.layer_grads.{name}"), bytes);
            enc.clear_buffer(&b, 0, None);
            b
        };
        let grads = Self {
            color: zeroed("color", pixels * 16),
            reflection: zeroed("reflection", pixels * 16),
            strength: zeroed("strength", pixels * 16),
            transmission: zeroed("transmission", pixels * 16),
            geometry: zeroed("geometry", pixels * 16),
            reflection_raw: zeroed("reflection_raw", slots * pixels * 16),
            size: (frame.width(), frame.height()),
        };
        ctx.queue.submit([enc.finish()]);
        grads
    }

    /// Upload gradients computed on the CPU (the twin's [`FrameGrads`] layout), checking that
    /// every image has the frame's size and that every value is finite: a bad gradient is
    /// rejected here, before any kernel runs.
    pub fn upload(
        ctx: &GpuContext,
        frame: &Frame,
        g: &FrameGrads,
    ) -> Result<Self, LayerGradsError> {
        let (w, h) = (frame.width(), frame.height());
        if g.planes.len() != frame.plane_count() {
            return Err(LayerGradsError::Planes {
                layer: "planes",
                got: g.planes.len(),
                want: frame.plane_count(),
            });
        }
        let mut raw = Vec::with_capacity(frame.plane_slots() * (w * h) as usize);
        for p in &g.planes {
            raw.extend(pack(
                w,
                h,
                &[("raw_color", &p.raw_color, 3, 0), ("intensity", &p.intensity, 1, 3)],
            )?);
        }
        raw.resize(frame.plane_slots() * (w * h) as usize, [0.0; 4]);
        let up = |name: &str, data: &[[f32; 4]]| {
            gpu::storage_init(ctx, &format!("trgs.layer_grads.{name}"), data)
        };
        let scopes = gpu::ErrorScopes::open(ctx, "uploading layer gradients");
        let grads = Ok(Self {
            color: up("color", &pack(w, h, &[("color", &g.color, 3, 0)])?),
            reflection: up("reflection", &pack(w, h, &[("reflection", &g.reflection, 3, 0)])?),
            strength: up(
                "strength",
                &pack(
                    w,
                    h,
                    &[("strength_raw", &g.strength_raw, 1, 0), ("strength", &g.strength, 1, 1)],
                )?,
            ),
            transmission: up(
                "transmission",
                &pack(w, h, &[("transmission", &g.transmission, 3, 0), ("alpha", &g.alpha, 1, 3)])?,
            ),
            geometry: up(
                "geometry",
                &pack(
                    w,
                    h,
                    &[
                        ("depth", &g.depth, 1, 0),
                        ("depth_variance", &g.depth_variance, 1, 1),
                        ("mask", &g.mask, 1, 2),
                    ],
                )?,
            ),
            reflection_raw: up("reflection_raw", &raw),
            size: (w, h),
        });
        scopes.close_after(grads)
    }
}
