//! Stages `exposure` and `exposure_bwd` on the GPU (shaders/training/exposure.wgsl and
//! exposure_bwd.wgsl; twins `trgs_core::reference::exposure` and `exposure_bwd`): the training
//! view's affine colour map applied to the render before the photometric loss, and its adjoint
//! after it, which turns dL/dC' into dL/dC in place and sums dL/d(A, b) over strips of
//! [`LOSS_STRIP`] pixels for the CPU (three vec4 a strip: 6 KB at 480x270).
use crate::kernels::TRAINING_KERNELS;
use crate::layout::{ExposureParams, LOSS_STRIP};
use trgs_core::pipeline::ExposureMatrix;
use trgs_render::GpuContext;
use trgs_render::toolkit::gpu::{self, BufferPool, Kernel, Recorder, grid_1d};

/// Side of the square workgroups of `exposure`.
const BLOCK: u32 = 16;

/// The two kernels and the exposed image's buffer (kept from step to step).
#[derive(Debug)]
pub struct ExposureKernels {
    exposure: Kernel,
    exposure_bwd: Kernel,
    scratch: BufferPool,
}

/// The strips' sums of dL/d(A, b) of a recorded `exposure_bwd`, to read once it has run.
#[derive(Debug)]
pub struct PendingExposureGrad {
    partials: wgpu::Buffer,
    strips: u32,
}

impl PendingExposureGrad {
    /// The sums on the GPU ([`PendingExposureGrad::vec4s`] of them), for the step's readback.
    pub fn partials(&self) -> &wgpu::Buffer {
        &self.partials
    }

    pub fn vec4s(&self) -> u32 {
        3 * self.strips
    }

    /// dL/d(A, b) from the sums as read back (`vec4s` of them), added up in f64.
    pub fn gradient_of(&self, partials: &[[f32; 4]]) -> ExposureMatrix {
        let mut g = [[0.0; 4]; 3];
        for strip in partials.chunks_exact(3) {
            for (row, sums) in g.iter_mut().zip(strip) {
                for (v, s) in row.iter_mut().zip(sums) {
                    *v += f64::from(*s);
                }
            }
        }
        g
    }
}

fn params(m: &ExposureMatrix, width: u32, height: u32) -> ExposureParams {
    let row = |i: usize| m[i].map(|v| v as f32);
    ExposureParams { row0: row(0), row1: row(1), row2: row(2), width, height, ..Default::default() }
}

impl ExposureKernels {
    pub fn new(ctx: &GpuContext) -> Self {
        let k = &TRAINING_KERNELS;
        Self {
            exposure: k.exposure.build(ctx),
            exposure_bwd: k.exposure_bwd.build(ctx),
            scratch: BufferPool::default(),
        }
    }

    /// Bytes of the kept buffers.
    pub fn scratch_bytes(&self) -> u64 {
        self.scratch.bytes()
    }

    /// Record `rendered` (vec4 per pixel of a `width` x `height` frame) mapped by `m`; returns
    /// the exposed image's buffer, laid out as `rendered`.
    pub fn record_exposure(
        &mut self,
        ctx: &GpuContext,
        rec: &mut Recorder,
        rendered: &wgpu::Buffer,
        (width, height): (u32, u32),
        m: &ExposureMatrix,
    ) -> wgpu::Buffer {
        let pixels = u64::from(width) * u64::from(height);
        let exposed = self.scratch.get(ctx, "trgs.exposure.exposed", pixels * 16);
        let block = gpu::params(ctx, "trgs.exposure.params", &params(m, width, height));
        let bind = self.exposure.bind(
            ctx,
            &[block.as_entire_binding(), rendered.as_entire_binding(), exposed.as_entire_binding()],
        );
        let groups = [width.div_ceil(BLOCK), height.div_ceil(BLOCK), 1];
        rec.dispatch("exposure", &self.exposure, &bind, groups);
        exposed
    }

    /// Record the adjoint: `grad_color` (dL/dC' per pixel) becomes dL/dC in place, and the
    /// strips' sums of dL/d(A, b) are left to read.
    pub fn record_exposure_bwd(
        &mut self,
        ctx: &GpuContext,
        rec: &mut Recorder,
        rendered: &wgpu::Buffer,
        grad_color: &wgpu::Buffer,
        (width, height): (u32, u32),
        m: &ExposureMatrix,
    ) -> PendingExposureGrad {
        let strips = (width * height).div_ceil(LOSS_STRIP);
        let partials = self.scratch.get(ctx, "trgs.exposure_bwd.partials", u64::from(strips) * 48);
        let block = gpu::params(ctx, "trgs.exposure_bwd.params", &params(m, width, height));
        let bind = self.exposure_bwd.bind(
            ctx,
            &[
                block.as_entire_binding(),
                rendered.as_entire_binding(),
                grad_color.as_entire_binding(),
                partials.as_entire_binding(),
            ],
        );
        rec.dispatch("exposure_bwd", &self.exposure_bwd, &bind, grid_1d(strips.div_ceil(64)));
        PendingExposureGrad { partials, strips }
    }
}
