//! The training losses on the GPU, writing dL/d(layer) where the backward pass reads it:
//! - stage `photometric_loss`: 3DGS's `(1 - lambda) L1 + lambda (1 - SSIM)` with the 11x11
//!   window, into dL/dC, as four separable passes (`photometric_loss_rows`, `photometric_loss`,
//!   `photometric_loss_grad_rows`, `photometric_loss_grad`), over the three colour channels at
//!   once where their scratch buffers fit one binding ([`ChannelPasses`]), else once per
//!   channel;
//! - stage `regularisers`: the paper's L_d, L_c and L_m, into dL/d(C_t, alpha) and
//!   dL/d(D_t, V, M);
//! - stage `loss_sums`: their per-pixel values summed over strips of pixels.
//!
//! The first two have their f64 twins of the same name in `trgs_core::reference`; `loss_sums` is a
//! plain sum, checked through the loss values those twins return (tests/losses.rs, at sizes with
//! one and with several workgroups of strips). A view's target
//! image and glass labels are uploaded ([`GpuTarget`], kept under a budget by
//! [`crate::trainer::targets::TargetCache`]); only the strips'
//! sums (32 bytes per strip of LOSS_STRIP pixels: 32 KB at 256x256) come back, for the step's
//! statistics.
pub mod step_guard;

use crate::kernels::TRAINING_KERNELS;
use crate::layout::{LOSS_BLUR_RUN, LOSS_STRIP, LossParams, UNCOVERED_LABEL};
use trgs_core::Image;
use trgs_core::pipeline::RegulariserWeights;
use trgs_render::toolkit::FrameStages;
use trgs_render::toolkit::gpu::{self, BufferPool, GpuError, Kernel, Recorder};
use trgs_render::{Frame, GpuContext, LayerGrads};

/// Side of the square workgroups of the per-pixel passes.
const BLOCK: u32 = 16;

#[derive(Debug, thiserror::Error)]
pub enum LossError {
    #[error("target image {name}: {channels} channels, the loss needs RGB")]
    Channels { name: String, channels: u32 },
    #[error("glass mask of {name}: {got_w}x{got_h}, its image is {want_w}x{want_h}")]
    MaskSize { name: String, got_w: u32, got_h: u32, want_w: u32, want_h: u32 },
    #[error("coverage of {name}: {got_w}x{got_h}, its image is {want_w}x{want_h}")]
    CoverageSize { name: String, got_w: u32, got_h: u32, want_w: u32, want_h: u32 },
    #[error("target image {name} is {got_w}x{got_h}, the rendered frame {want_w}x{want_h}")]
    FrameSize { name: String, got_w: u32, got_h: u32, want_w: u32, want_h: u32 },
    #[error("the frame has not been rendered")]
    NotRendered,
    #[error(
        "training at {width}x{height}: the loss's {buffer} buffer needs {bytes} bytes in one \
         binding, the device allows {limit}; train at a lower resolution (--resolution or \
         --downscale)"
    )]
    TooLarge { width: u32, height: u32, buffer: &'static str, bytes: u64, limit: u64 },
}

/// Bytes per pixel and channel of a run of the photometric passes of the loss's scratch
/// buffers `rows` (five moments) and `terms` (three derivatives), and per pixel of `stats` (two
/// vec4).
const ROWS_BYTES_PER_CHANNEL: u64 = 20;
const TERMS_BYTES_PER_CHANNEL: u64 = 12;
const STATS_BYTES_PER_PIXEL: u64 = 32;

/// How the photometric loss's four passes cover the colour channels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChannelPasses {
    /// One run over R, G and B: each tap's pixel is read once for the three, a third of the
    /// dispatches (`bench --train-step` times the loss phase). Its scratch needs 60 bytes a
    /// pixel in one binding.
    Rgb,
    /// One run per channel, a third of the scratch: for frames whose RGB scratch would not fit
    /// one binding (about 2.2 million pixels under a 128 MiB limit).
    PerChannel,
}

impl ChannelPasses {
    /// RGB where its scratch fits the device's binding limit, else one channel at a time.
    pub fn for_frame(ctx: &GpuContext, width: u32, height: u32) -> Self {
        let pixels = u64::from(width) * u64::from(height);
        if pixels * 3 * ROWS_BYTES_PER_CHANNEL <= ctx.binding_limit() {
            Self::Rgb
        } else {
            Self::PerChannel
        }
    }

    /// Channels per run.
    fn channels(self) -> u32 {
        match self {
            Self::Rgb => 3,
            Self::PerChannel => 1,
        }
    }
}

/// A view's target image and glass labels on the GPU. The image is stored as 8-bit RGBA (4 bytes
/// a pixel, a quarter of f32 RGBA), as 3DGS keeps its 8-bit images: a dataset of a few hundred
/// views then fits next to the model. Alpha is the pixel's coverage: 1 where the photo has a
/// source, 0 where it has none (the border of an undistorted photo), which the losses leave out
/// (`photometric_loss_covered`; the label is then [`UNCOVERED_LABEL`]).
#[derive(Debug)]
pub struct GpuTarget {
    name: String,
    width: u32,
    height: u32,
    image: wgpu::Buffer,
    annotation: Option<wgpu::Buffer>,
}

impl GpuTarget {
    /// Upload `image` (RGB), its glass labels `mask` and its coverage `covered` (same size; None:
    /// every pixel), if any.
    pub fn upload(
        ctx: &GpuContext,
        name: &str,
        image: &Image<u8>,
        mask: Option<&Image<u8>>,
        covered: Option<&Image<u8>>,
    ) -> Result<Self, LossError> {
        if image.channels != 3 {
            return Err(LossError::Channels { name: name.to_string(), channels: image.channels });
        }
        if let Some(c) =
            covered.filter(|c| (c.width, c.height, c.channels) != (image.width, image.height, 1))
        {
            return Err(LossError::CoverageSize {
                name: name.to_string(),
                got_w: c.width,
                got_h: c.height,
                want_w: image.width,
                want_h: image.height,
            });
        }
        let is_covered = |i: usize| covered.is_none_or(|c| c.data[i] != 0);
        let rgb: Vec<u32> = image
            .data
            .chunks(3)
            .enumerate()
            .map(|(i, c)| {
                let alpha = if is_covered(i) { 255 } else { 0 };
                u32::from_le_bytes([c[0], c[1], c[2], alpha])
            })
            .collect();
        let annotation = match mask {
            Some(m) if (m.width, m.height) != (image.width, image.height) || m.channels != 1 => {
                return Err(LossError::MaskSize {
                    name: name.to_string(),
                    got_w: m.width,
                    got_h: m.height,
                    want_w: image.width,
                    want_h: image.height,
                });
            }
            Some(m) => {
                let labels: Vec<u32> = m
                    .data
                    .iter()
                    .enumerate()
                    .map(|(i, &v)| if is_covered(i) { u32::from(v) } else { UNCOVERED_LABEL })
                    .collect();
                Some(gpu::storage_init(ctx, &format!("trgs.target.{name}.annotation"), &labels))
            }
            None => None,
        };
        Ok(Self {
            name: name.to_string(),
            width: image.width,
            height: image.height,
            image: gpu::storage_init(ctx, &format!("trgs.target.{name}.image"), &rgb),
            annotation,
        })
    }

    pub fn has_annotation(&self) -> bool {
        self.annotation.is_some()
    }
}

/// The loss weights of a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LossSettings {
    /// The D-SSIM weight lambda.
    pub lambda_dssim: f64,
    /// The regularisers' weights; `None` skips stage `regularisers` (a frame without planes).
    pub regularisers: Option<RegulariserWeights>,
}

/// Whether the losses' scratch buffers of a `width x height` frame fit the device: each is one
/// binding, and above the device's binding limit wgpu would fail validation, so that is an error
/// here (a run checks every view's training size before it loads the photos).
pub fn check_frame_size(ctx: &GpuContext, width: u32, height: u32) -> Result<(), LossError> {
    let pixels = u64::from(width) * u64::from(height);
    let limit = ctx.binding_limit();
    for (buffer, per_pixel) in [
        ("row", ROWS_BYTES_PER_CHANNEL),
        ("derivative", TERMS_BYTES_PER_CHANNEL),
        ("statistics", STATS_BYTES_PER_PIXEL),
    ] {
        let bytes = pixels * per_pixel;
        if bytes > limit {
            return Err(LossError::TooLarge { width, height, buffer, bytes, limit });
        }
    }
    Ok(())
}

/// The values of a step's losses, from the strips' sums (f32 on the GPU, summed in
/// f64 here). The regularisers' values are unweighted; a zero weight leaves its value at zero.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LossValues {
    /// `(1 - lambda) l1 + lambda (1 - ssim)`.
    pub value: f64,
    pub l1: f64,
    pub ssim: f64,
    /// Mean squared error of the rendered image.
    pub mse: f64,
    pub depth: f64,
    pub conflict: f64,
    pub mask: f64,
}

/// What [`LossKernels::record`] leaves to read once its work has run.
#[derive(Debug)]
pub struct PendingLoss {
    partials: wgpu::Buffer,
    regularisers: bool,
    strips: usize,
    lambda_dssim: f64,
    inv_samples: f64,
    inv_pixels: f64,
}

impl PendingLoss {
    /// Sum the strips' sums (blocking read of 32 bytes per strip).
    pub fn read(&self, ctx: &GpuContext) -> Result<LossValues, GpuError> {
        let partials = gpu::read_buffer::<[f32; 4]>(ctx, &self.partials, 0, 2 * self.strips)?;
        Ok(self.values_of(&partials))
    }

    /// The strips' sums on the GPU ([`PendingLoss::partial_vec4s`] vec4s), for a readback of
    /// the caller's own.
    pub fn partials(&self) -> &wgpu::Buffer {
        &self.partials
    }

    /// How many vec4s of sums [`PendingLoss::partials`] holds (two per strip).
    pub fn partial_vec4s(&self) -> u32 {
        2 * self.strips as u32
    }

    /// The values from the strips' sums as read back (`partial_vec4s` of them).
    pub fn values_of(&self, partials: &[[f32; 4]]) -> LossValues {
        let total = |slot: usize| {
            partials.iter().skip(slot).step_by(2).fold([0.0f64; 3], |acc, p| {
                [acc[0] + f64::from(p[0]), acc[1] + f64::from(p[1]), acc[2] + f64::from(p[2])]
            })
        };
        let [l1, ssim, sq] = total(0).map(|v| v * self.inv_samples);
        let [depth, conflict, mask] = if self.regularisers {
            let [d, c, m] = total(1);
            [d * self.inv_pixels, c * self.inv_samples, m * self.inv_pixels]
        } else {
            [0.0; 3]
        };
        let lambda = self.lambda_dssim;
        LossValues {
            value: (1.0 - lambda) * l1 + lambda * (1.0 - ssim),
            l1,
            ssim,
            mse: sq,
            depth,
            conflict,
            mask,
        }
    }
}

/// The layers the losses read: a rendered frame's, or any buffers laid out like them.
#[derive(Clone, Copy, Debug)]
pub struct LossLayers<'a> {
    pub width: u32,
    pub height: u32,
    /// The image: (C, -) per pixel; only RGB is read.
    pub color: &'a wgpu::Buffer,
    /// (C_t, 1 - T_t)
    pub transmission: &'a wgpu::Buffer,
    /// (C_r, -)
    pub reflection: &'a wgpu::Buffer,
    /// (D_t, V, M, -)
    pub geometry: &'a wgpu::Buffer,
    /// The plane hit by each pixel's ray (u32, 0: none).
    pub hit: &'a wgpu::Buffer,
}

impl<'a> LossLayers<'a> {
    /// The layers of a rendered frame.
    pub fn of_frame(frame: &'a Frame) -> Result<Self, LossError> {
        let l = frame.layer_buffers().ok_or(LossError::NotRendered)?;
        Ok(Self {
            width: frame.width(),
            height: frame.height(),
            // Without a composite the transmission layer's RGB is the image.
            color: if frame.composed() { &l.color } else { &l.transmission },
            transmission: &l.transmission,
            reflection: &l.reflection,
            geometry: &l.geometry,
            hit: &l.hit,
        })
    }
}

/// The buffers the four passes of stage `photometric_loss` read and write.
struct PhotometricBuffers<'a> {
    rendered: &'a wgpu::Buffer,
    image: &'a wgpu::Buffer,
    rows: &'a wgpu::Buffer,
    terms: &'a wgpu::Buffer,
    stats: &'a wgpu::Buffer,
    grad_color: &'a wgpu::Buffer,
}

/// The four passes of stage `photometric_loss` in one variant (RGB or one channel).
#[derive(Debug)]
struct PhotometricPasses {
    rows: Kernel,
    loss: Kernel,
    grad_rows: Kernel,
    grad: Kernel,
}

impl PhotometricPasses {
    fn build(ctx: &GpuContext, passes: ChannelPasses) -> Self {
        let k = &TRAINING_KERNELS;
        match passes {
            ChannelPasses::Rgb => Self {
                rows: k.photometric_loss_rows_rgb.build(ctx),
                loss: k.photometric_loss_rgb.build(ctx),
                grad_rows: k.photometric_loss_grad_rows_rgb.build(ctx),
                grad: k.photometric_loss_grad_rgb.build(ctx),
            },
            ChannelPasses::PerChannel => Self {
                rows: k.photometric_loss_rows.build(ctx),
                loss: k.photometric_loss.build(ctx),
                grad_rows: k.photometric_loss_grad_rows.build(ctx),
                grad: k.photometric_loss_grad.build(ctx),
            },
        }
    }

    /// Record one run of the four passes over a `w x h` frame (`block`: the run's parameters).
    /// Pass 1 takes a pixel a thread; the others a run of LOSS_BLUR_RUN pixels along x (row
    /// blur) or y (column blur).
    fn record(
        &self,
        ctx: &GpuContext,
        rec: &mut Recorder,
        block: &wgpu::Buffer,
        (w, h): (u32, u32),
        b: &PhotometricBuffers<'_>,
    ) {
        let per_pixel = [w.div_ceil(BLOCK), h.div_ceil(BLOCK), 1];
        let along_rows = [w.div_ceil(BLOCK * LOSS_BLUR_RUN), h.div_ceil(BLOCK), 1];
        let along_columns = [w.div_ceil(BLOCK), h.div_ceil(BLOCK * LOSS_BLUR_RUN), 1];
        let passes: [(&'static str, &Kernel, Vec<&wgpu::Buffer>, [u32; 3]); 4] = [
            ("photometric_loss_rows", &self.rows, vec![b.rendered, b.image, b.rows], per_pixel),
            (
                "photometric_loss",
                &self.loss,
                vec![b.rendered, b.image, b.rows, b.terms, b.stats],
                along_columns,
            ),
            ("photometric_loss_grad_rows", &self.grad_rows, vec![b.terms, b.rows], along_rows),
            (
                "photometric_loss_grad",
                &self.grad,
                vec![b.rendered, b.image, b.rows, b.grad_color],
                along_columns,
            ),
        ];
        for (stage, kernel, buffers, groups) in passes {
            let mut entries = vec![block.as_entire_binding()];
            entries.extend(buffers.iter().map(|b| b.as_entire_binding()));
            rec.dispatch(stage, kernel, &kernel.bind(ctx, &entries), groups);
        }
    }
}

/// The loss pipelines, compiled once (each photometric variant when first used).
#[derive(Debug)]
pub struct LossKernels {
    rgb: Option<PhotometricPasses>,
    per_channel: Option<PhotometricPasses>,
    /// Set: every frame uses these passes (tests); None: [`ChannelPasses::for_frame`].
    forced: Option<ChannelPasses>,
    regularisers: Kernel,
    loss_sums: Kernel,
    scratch: BufferPool,
}

impl LossKernels {
    pub fn new(ctx: &GpuContext) -> Self {
        Self::with_channel_passes(ctx, None)
    }

    /// Kernels whose photometric passes are `forced` on every frame (None: chosen per frame).
    pub fn with_channel_passes(ctx: &GpuContext, forced: Option<ChannelPasses>) -> Self {
        let k = &TRAINING_KERNELS;
        Self {
            rgb: None,
            per_channel: None,
            forced,
            regularisers: k.regularisers.build(ctx),
            loss_sums: k.loss_sums.build(ctx),
            scratch: BufferPool::default(),
        }
    }

    /// The passes of `variant`, built on first use.
    fn photometric(&mut self, ctx: &GpuContext, variant: ChannelPasses) -> &PhotometricPasses {
        let slot = match variant {
            ChannelPasses::Rgb => &mut self.rgb,
            ChannelPasses::PerChannel => &mut self.per_channel,
        };
        slot.get_or_insert_with(|| PhotometricPasses::build(ctx, variant))
    }

    /// Bytes of the scratch buffers (kept from step to step).
    pub fn scratch_bytes(&self) -> u64 {
        self.scratch.bytes()
    }

    /// Record the losses of `layers` against `target` into `grads`. Every gradient layer the
    /// backward accumulates into is reset first, so `grads` can be reused step after step.
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        rec: &mut Recorder,
        layers: &LossLayers<'_>,
        target: &GpuTarget,
        grads: &LayerGrads,
        settings: &LossSettings,
    ) -> Result<PendingLoss, LossError> {
        let (w, h) = (layers.width, layers.height);
        if (target.width, target.height) != (w, h) {
            return Err(LossError::FrameSize {
                name: target.name.clone(),
                got_w: target.width,
                got_h: target.height,
                want_w: w,
                want_h: h,
            });
        }
        for b in [&grads.transmission, &grads.geometry, &grads.reflection_raw] {
            rec.encoder.clear_buffer(b, 0, None);
        }
        let pixels = u64::from(w) * u64::from(h);
        let groups = [w.div_ceil(BLOCK), h.div_ceil(BLOCK), 1];
        let strips = (pixels as u32).div_ceil(LOSS_STRIP);
        let weights = settings.regularisers.unwrap_or_default();
        let params = LossParams {
            width: w,
            height: h,
            lambda_dssim: settings.lambda_dssim as f32,
            inv_samples: (1.0 / (3 * pixels).max(1) as f64) as f32,
            inv_pixels: (1.0 / pixels.max(1) as f64) as f32,
            weight_depth: weights.depth as f32,
            weight_conflict: weights.conflict as f32,
            weight_mask: if target.has_annotation() { weights.mask as f32 } else { 0.0 },
            channel: 0,
            regularisers: u32::from(settings.regularisers.is_some()),
        };
        let block = gpu::params(ctx, "trgs.photometric_loss.params", &params);
        let (rendered, image) = (layers.color, &target.image);
        check_frame_size(ctx, w, h)?;
        let variant = self.forced.unwrap_or_else(|| ChannelPasses::for_frame(ctx, w, h));
        let per_run = u64::from(variant.channels());
        let rows = self.scratch.get(
            ctx,
            "trgs.photometric_loss.rows",
            pixels * per_run * ROWS_BYTES_PER_CHANNEL,
        );
        let terms = self.scratch.get(
            ctx,
            "trgs.photometric_loss.terms",
            pixels * per_run * TERMS_BYTES_PER_CHANNEL,
        );
        let stats = self.scratch.get(ctx, "trgs.loss_sums.stats", pixels * STATS_BYTES_PER_PIXEL);
        let partials = self.scratch.get(ctx, "trgs.loss_sums.partials", u64::from(strips) * 32);
        let passes = self.photometric(ctx, variant);
        for channel in (0..3).step_by(variant.channels() as usize) {
            let block = gpu::params(
                ctx,
                "trgs.photometric_loss.channel_params",
                &LossParams { channel, ..params },
            );
            let buffers = PhotometricBuffers {
                rendered,
                image,
                rows: &rows,
                terms: &terms,
                stats: &stats,
                grad_color: &grads.color,
            };
            passes.record(ctx, rec, &block, (w, h), &buffers);
        }
        if settings.regularisers.is_some() {
            // Bound but never read when the view has no labels.
            let annotation = target.annotation.as_ref().unwrap_or(layers.hit);
            let bind = self.regularisers.bind(
                ctx,
                &[
                    block.as_entire_binding(),
                    layers.transmission.as_entire_binding(),
                    layers.reflection.as_entire_binding(),
                    layers.geometry.as_entire_binding(),
                    layers.hit.as_entire_binding(),
                    annotation.as_entire_binding(),
                    grads.transmission.as_entire_binding(),
                    grads.geometry.as_entire_binding(),
                    stats.as_entire_binding(),
                ],
            );
            rec.dispatch("regularisers", &self.regularisers, &bind, groups);
        }
        let bind = self.loss_sums.bind(
            ctx,
            &[block.as_entire_binding(), stats.as_entire_binding(), partials.as_entire_binding()],
        );
        rec.dispatch("loss_sums", &self.loss_sums, &bind, gpu::grid_1d(strips.div_ceil(64)));
        Ok(PendingLoss {
            partials,
            regularisers: settings.regularisers.is_some(),
            strips: strips as usize,
            lambda_dssim: settings.lambda_dssim,
            inv_samples: 1.0 / (3 * pixels).max(1) as f64,
            inv_pixels: 1.0 / pixels.max(1) as f64,
        })
    }
}
