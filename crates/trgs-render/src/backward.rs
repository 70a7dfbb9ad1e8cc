//! The backward pass on the GPU: from dL/d(each layer of a frame) to the gradients of every
//! Gaussian attribute (in GPU buffers shaped like the scene's) and of every plane's centre,
//! normal and R0 logit. The order is the reverse of the forward's (docs/ARCHITECTURE.md, "Data
//! flow"): compose_bwd; rasterize_bwd and project_bwd of the real view; per plane
//! rasterize_reflection_bwd and project_bwd of its mirrored view, whose view gradient then chains
//! into the plane on the CPU when it is read back ([`PlaneGradsRead`]). The pass is submitted and
//! not waited for.
use crate::GpuContext;
use crate::frame::{BackwardBuffers, Frame, LayerBuffers, ViewBuffers};
use crate::gpu::{self, GpuError, KernelTime, PendingRead, Recorder};
use crate::layer_grads::LayerGrads;
use crate::layout::{BWD_ADD, BWD_NO_GAUSSIANS, BWD_VIEW, PROJECTED_GRAD_FLOATS, VIEW_GRAD_FLOATS};
use crate::renderer::Renderer;
use crate::scene::{GpuScene, SceneGradBuffers};
use crate::stages::rasterize_bwd::ViewLists;
use crate::stages::{Stage, compose_bwd, project_bwd, rasterize_bwd, rasterize_reflection_bwd};
use crate::toolkit::FrameStages;
use crate::toolkit::paged::Paged;
use trgs_core::pipeline::TileGrid;

mod plane_grads;
pub use plane_grads::PlaneGradsRead;

/// Switches of the backward pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BackwardOptions {
    /// Stage 2 of training: no gradient from the mirrored passes (C_r) into any Gaussian; the
    /// planes' centre and normal still learn from them through the mirrored view.
    pub block_reflection_to_gaussians: bool,
    /// Time every stage with timestamp queries when the adapter has them.
    pub profile: bool,
}

/// The result of [`Renderer::backward`].
#[derive(Debug)]
pub struct Gradients {
    /// dL/d(each Gaussian attribute), on the GPU.
    pub gaussians: SceneGradBuffers,
    /// dL/d(each plane's centre, unnormalised normal, R0 logit), read back on demand
    /// ([`PlaneGradsRead::read`]): the backward does not wait for them.
    pub planes: PlaneGradsRead,
    /// Per view (0 = camera, then each mirrored pass): the screen-space gradients.
    projected_grads: Vec<Paged>,
    stage_times: Option<Vec<(&'static str, f64)>>,
    kernel_times: Option<Vec<KernelTime>>,
}

impl crate::toolkit::GradientStages for Gradients {
    fn read_projected_grads(
        &self,
        ctx: &crate::GpuContext,
        vi: usize,
    ) -> Result<Option<Vec<[f32; PROJECTED_GRAD_FLOATS as usize]>>, GpuError> {
        let Some(b) = self.projected_grads.get(vi) else {
            return Ok(None);
        };
        b.read(ctx).map(Some)
    }

    fn projected_grads(&self, vi: usize) -> Option<&Paged> {
        self.projected_grads.get(vi)
    }
}

impl Gradients {
    /// Milliseconds per stage, with `profile` on an adapter with timestamps.
    pub fn stage_times(&self) -> Option<&[(&'static str, f64)]> {
        self.stage_times.as_deref()
    }

    /// The stage times split by kernel, with `profile`.
    pub fn kernel_times(&self) -> Option<&[KernelTime]> {
        self.kernel_times.as_deref()
    }
}

#[derive(Debug, thiserror::Error)]
pub enum BackwardError {
    #[error("the frame has not been rendered")]
    NotRendered,
    #[error(
        "the frame was rendered from {frame_gaussians} Gaussians and {frame_planes} planes, the \
         scene has {scene_gaussians} and {scene_planes}"
    )]
    SceneMismatch {
        frame_gaussians: u32,
        frame_planes: usize,
        scene_gaussians: u32,
        scene_planes: usize,
    },
    #[error(
        "the gradient of layer {layer} holds {bytes} bytes, the frame needs {needed}: were the \
         gradients made for another frame?"
    )]
    GradsTooSmall { layer: &'static str, bytes: u64, needed: u64 },
    #[error(
        "the gradients were made for a {}x{} frame, the frame is {}x{}", grads.0, grads.1,
        frame.0, frame.1
    )]
    GradsForAnotherSize { grads: (u32, u32), frame: (u32, u32) },
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

impl Renderer {
    /// Gradients of a scalar loss from dL/d(each layer of `frame`), which this renderer rendered
    /// from `scene` (same Gaussians and planes, unchanged since). `grads` is consumed: its
    /// pass-layer buffers hold compose's totals afterwards. The Gaussian gradient buffers belong
    /// to `frame` and are overwritten by its next backward.
    pub fn backward(
        &self,
        scene: &GpuScene,
        frame: &mut Frame,
        grads: &LayerGrads,
        options: &BackwardOptions,
    ) -> Result<Gradients, BackwardError> {
        gpu::scoped(&self.ctx, "computing gradients", || {
            self.backward_scoped(scene, frame, grads, options)
        })
    }

    /// The backward, phase by phase: check the inputs, clear the gradient buffers, compose_bwd,
    /// each view's replay, then the plane readback, submitted without a wait.
    fn backward_scoped(
        &self,
        scene: &GpuScene,
        frame: &mut Frame,
        grads: &LayerGrads,
        options: &BackwardOptions,
    ) -> Result<Gradients, BackwardError> {
        let ctx = &self.ctx;
        let grid = check_inputs(scene, frame, grads)?;
        let bufs = frame.backward_buffers(ctx, scene);
        let frame = &*frame;
        #[allow(clippy::expect_used)]
        let (layers, rays) = (
            frame.layer_buffers().expect("checked above"),
            frame.rays().expect("a rendered frame keeps its rays"),
        );
        let s = Stage { ctx, kernels: &self.kernels };
        let mut rec = Recorder::new(ctx, "trgs.backward", options.profile);
        clear_gradients(&mut rec, &bufs);
        compose_bwd::record(s, &mut rec, &grid, rays, layers, grads, &bufs.plane_grads);
        let replay = ViewReplay { s, scene, frame, grid, layers, grads, options, bufs: &bufs };
        for (vi, v) in frame.views().iter().enumerate() {
            replay.record(&mut rec, vi, v);
        }
        let planes = read_plane_grads(&mut rec, ctx, scene, frame, &bufs)?;
        Ok(Gradients {
            gaussians: bufs.scene_grads,
            planes,
            projected_grads: bufs.projected_grads,
            stage_times: rec.stage_times(),
            kernel_times: rec.kernel_times(),
        })
    }
}

/// Checks that `frame` was rendered, from a scene shaped like `scene`, and that `grads` were
/// made for it. Returns its tile grid.
fn check_inputs(
    scene: &GpuScene,
    frame: &Frame,
    grads: &LayerGrads,
) -> Result<TileGrid, BackwardError> {
    let (Some(grid), Some(_)) = (frame.grid(), frame.layer_buffers()) else {
        return Err(BackwardError::NotRendered);
    };
    if frame.gaussian_count() != scene.len() || frame.plane_count() != scene.planes().len() {
        return Err(BackwardError::SceneMismatch {
            frame_gaussians: frame.gaussian_count(),
            frame_planes: frame.plane_count(),
            scene_gaussians: scene.len(),
            scene_planes: scene.planes().len(),
        });
    }
    if grads.size != (frame.width(), frame.height()) {
        return Err(BackwardError::GradsForAnotherSize {
            grads: grads.size,
            frame: (frame.width(), frame.height()),
        });
    }
    // Buffers made by hand (the fields are public) may still be short.
    if let Some((layer, bytes, needed)) = grads.too_small_for(frame) {
        return Err(BackwardError::GradsTooSmall { layer, bytes, needed });
    }
    Ok(grid)
}

/// Zeroes every buffer the backward adds into.
fn clear_gradients(rec: &mut Recorder, bufs: &BackwardBuffers) {
    for b in &bufs.projected_grads {
        b.clear(&mut rec.encoder);
    }
    rec.encoder.clear_buffer(&bufs.view_grads, 0, None);
    rec.encoder.clear_buffer(&bufs.plane_grads, 0, None);
    bufs.scene_grads.clear(&mut rec.encoder);
}

/// What the replay of each view reads and writes.
struct ViewReplay<'a> {
    s: Stage<'a>,
    scene: &'a GpuScene,
    frame: &'a Frame,
    grid: TileGrid,
    layers: &'a LayerBuffers,
    grads: &'a LayerGrads,
    options: &'a BackwardOptions,
    bufs: &'a BackwardBuffers,
}

impl ViewReplay<'_> {
    /// The adjoint of view `vi`'s pass into its screen-space gradients, then project_bwd from
    /// them into the Gaussians' gradients and the view's gradient slot.
    fn record(&self, rec: &mut Recorder, vi: usize, v: &ViewBuffers) {
        let bufs = self.bufs;
        let mode = self.record_pass(rec, v, &bufs.projected_grads[vi]);
        let view_slot = gpu::range(
            &bufs.view_grads,
            vi as u64 * bufs.view_stride,
            u64::from(VIEW_GRAD_FLOATS) * 4,
        );
        project_bwd::record(
            self.s,
            rec,
            self.scene,
            &v.project_params,
            mode,
            &v.projected,
            &v.candidates,
            &bufs.projected_grads[vi],
            &bufs.scene_grads,
            view_slot,
        );
    }

    /// The adjoint of `v`'s rasterize pass (pass 1 for the camera, pass 2 for a mirrored view)
    /// into `pg`; returns the BWD_* bits project_bwd runs with: the camera writes the Gaussians'
    /// gradients, a mirrored view adds to them (or leaves them alone under stage 2's block) and
    /// sums its view's gradient.
    fn record_pass(&self, rec: &mut Recorder, v: &ViewBuffers, pg: &Paged) -> u32 {
        let (s, grid, layers, grads) = (self.s, &self.grid, self.layers, self.grads);
        #[allow(clippy::expect_used)]
        let lists = ViewLists {
            projected: &v.projected,
            values: &v.keys.as_ref().expect("a rendered view is sorted").values,
            ranges: v.ranges.as_ref().expect("a rendered view has ranges"),
        };
        match v.plane {
            None => {
                let (background, depth_variance) =
                    (self.frame.background(), self.frame.has_depth_variance());
                rasterize_bwd::record(
                    s,
                    rec,
                    grid,
                    background,
                    depth_variance,
                    lists,
                    layers,
                    grads,
                    pg,
                );
                0
            }
            Some(k) => {
                let (limit, tile_base) = (&v.limit, v.tile_base);
                rasterize_reflection_bwd::record(
                    s, rec, grid, k as u32, limit, tile_base, lists, layers, grads, pg,
                );
                let gaussians = if self.options.block_reflection_to_gaussians {
                    BWD_NO_GAUSSIANS
                } else {
                    BWD_ADD
                };
                BWD_VIEW | gaussians
            }
        }
    }
}

/// Submits the backward. The plane sums and view gradients come back in one small readback,
/// which the backward does not wait for (none without planes).
fn read_plane_grads(
    rec: &mut Recorder,
    ctx: &GpuContext,
    scene: &GpuScene,
    frame: &Frame,
    bufs: &BackwardBuffers,
) -> Result<PlaneGradsRead, GpuError> {
    if scene.planes().is_empty() {
        rec.submit(ctx)?;
        return Ok(PlaneGradsRead::default());
    }
    let views = frame.views();
    let plane_bytes = bufs.plane_grads.size().min(frame.plane_slots() as u64 * 16);
    let view_bytes = views.len() as u64 * bufs.view_stride;
    let bytes = plane_bytes + view_bytes;
    let staging = gpu::staging(ctx, "trgs.backward.plane_staging", bytes);
    let enc = &mut rec.encoder;
    enc.copy_buffer_to_buffer(&bufs.plane_grads, 0, &staging, 0, plane_bytes);
    enc.copy_buffer_to_buffer(&bufs.view_grads, 0, &staging, plane_bytes, view_bytes);
    let submission = rec.submit(ctx)?;
    let mirrored =
        (0..scene.planes().len()).map(|k| views.iter().position(|v| v.plane == Some(k))).collect();
    Ok(PlaneGradsRead::pending(
        PendingRead::after(staging, submission),
        scene.planes().to_vec(),
        views[0].view,
        mirrored,
        (plane_bytes, bufs.view_stride, bytes),
    ))
}
