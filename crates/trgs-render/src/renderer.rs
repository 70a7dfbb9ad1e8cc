//! The forward renderer: the stages of the data flow (docs/ARCHITECTURE.md) for one camera, into
//! a [`Frame`]. `Renderer::render_scoped` runs the phases of a render in order, one module each:
//! the checks (`checks`), the views (`job`), phase 1 (`binning`), the key list's size
//! (`key_sizing`), phase 2's key list (`key_list`) and its passes and compose (`passes`).
use crate::GpuContext;
use crate::frame::{Frame, KeySizing};
use crate::gpu::{self, GpuError, Recorder};
use crate::kernels::Kernels;
use crate::layer_grads::LayerGrads;
use crate::layout::PLANE_GRAD_FLOATS;
use crate::scene::GpuScene;
use crate::stages::{Stage, compose_bwd};
use crate::toolkit::FrameStages;
use binning::Binned;
use job::RenderJob;
use trgs_core::scene::Camera;

mod binning;
mod checks;
mod job;
mod key_list;
mod key_sizing;
mod options;
mod passes;

pub use options::{RenderError, RenderOptions};

/// Keys (4 bytes each) that one storage binding of `ctx` holds: a page of the key list.
fn keys_in_one_binding(ctx: &GpuContext) -> u32 {
    u32::try_from(ctx.binding_limit() / 4).unwrap_or(u32::MAX)
}

/// Renders [`GpuScene`]s on one device. Compiles its pipelines once.
#[derive(Debug)]
pub struct Renderer {
    pub(crate) ctx: GpuContext,
    pub(crate) kernels: Kernels,
    /// Keys in a page of the frame's key list ([`Renderer::set_key_page_len`]).
    key_page_len: u32,
}

impl Renderer {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            ctx: ctx.clone(),
            kernels: crate::kernels::RENDER_KERNELS.compile(ctx),
            key_page_len: keys_in_one_binding(ctx),
        }
    }

    /// Keys in one page of the frame's key list: as many as one binding holds unless set lower
    /// (tests split small frames to run the paged kernels). A frame holds at most
    /// [`MAX_PAGES`](crate::toolkit::paged::MAX_PAGES) pages of keys.
    pub fn key_page_len(&self) -> u32 {
        self.key_page_len
    }

    /// Pages the key list every `keys` keys (at most one binding's worth).
    pub fn set_key_page_len(&mut self, keys: u32) {
        self.key_page_len = keys.clamp(1, keys_in_one_binding(&self.ctx));
    }

    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// Render every layer of `camera`'s view into a new frame.
    pub fn render(
        &self,
        scene: &GpuScene,
        camera: &Camera,
        options: &RenderOptions,
    ) -> Result<Frame, RenderError> {
        let mut frame = Frame::default();
        self.render_into(scene, camera, options, &mut frame)?;
        Ok(frame)
    }

    /// Render into `frame`, reusing its buffers where they are large enough.
    pub fn render_into(
        &self,
        scene: &GpuScene,
        camera: &Camera,
        options: &RenderOptions,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        gpu::scoped(&self.ctx, "rendering a frame", || {
            self.render_scoped(scene, camera, options, frame)
        })
    }

    /// Render into `frame` and `finish` it (a pass that waits for the GPU: a display, or a plain
    /// wait), with one wait a frame: the key list is sized from earlier frames
    /// ([`KeySizing::FromEarlierFrames`], whatever `options` says), so the render does not wait
    /// halfway for its key totals, which `finish`'s wait brings back. A frame that outgrew its
    /// list dropped keys: it is rendered again, sized exactly, and finished again. How a viewer
    /// draws and how `render_fps` times a render.
    pub fn render_finished<E: From<RenderError>>(
        &self,
        scene: &GpuScene,
        camera: &Camera,
        options: &RenderOptions,
        frame: &mut Frame,
        mut finish: impl FnMut(&Frame) -> Result<(), E>,
    ) -> Result<(), E> {
        let sized = RenderOptions { key_sizing: KeySizing::FromEarlierFrames, ..options.clone() };
        self.render_into(scene, camera, &sized, frame)?;
        finish(frame)?;
        // Known without another wait: `finish` waited for the frame.
        let totals = frame.settle_keys(&self.ctx).map_err(RenderError::from)?;
        if totals.is_none_or(|k| k.held()) {
            return Ok(());
        }
        let exact = RenderOptions { key_sizing: KeySizing::Exact, ..options.clone() };
        self.render_into(scene, camera, &exact, frame)?;
        finish(frame)
    }

    /// One render, phase by phase (the module's docs). The frame is reset once the request is
    /// checked and the previous render's totals are settled: a render that fails after that
    /// leaves it "not rendered".
    fn render_scoped(
        &self,
        scene: &GpuScene,
        camera: &Camera,
        options: &RenderOptions,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        let ctx = &self.ctx;
        let grid = checks::check_request(ctx, scene, camera, options)?;
        let s = Stage { ctx, kernels: &self.kernels };
        let job = RenderJob { s, scene, camera, options, grid, key_page_len: self.key_page_len };
        let specs = job::plan_views(&job);
        // The previous render's totals, if still on their way, size this one's key list.
        frame.settle_keys(ctx)?;
        let (planes, n) = (scene.planes().len(), scene.len());
        frame.reset(grid, planes, n, options.depth_variance, options.background);
        let budget = key_sizing::key_budget(frame, options, self.key_page_len);
        checks::check_entries(ctx, camera, specs.len(), n)?;
        let mut rec = Recorder::new(ctx, "trgs.render", options.profile);
        let Binned { mut views, depth, totals } =
            binning::bin_views(&mut rec, &mut frame.pool, &job, &specs);
        let size = key_sizing::size_key_list(&mut rec, ctx, camera, &budget, &totals, &mut views)?;
        let binning =
            key_list::emit_and_sort(&mut rec, &mut frame.pool, &job, depth, &mut views, &size);
        let layers = frame.layers(ctx, job.pixels());
        let composed = passes::rasterize_and_compose(&mut rec, &job, &views, &layers);
        let submission = key_sizing::submit_render(&mut rec, ctx, &size)?;
        frame.finish(views, binning, composed.has_pass, Some(composed.rays), &rec);
        key_sizing::deliver_totals(frame, submission, &size, totals);
        Ok(())
    }

    /// The adjoint of `compose` alone, for `frame` as this renderer rendered it: adds compose's
    /// gradients into the pass-layer buffers of `grads` (direct gradients in, totals out) and
    /// returns each plane's (dL/dR0, dL/d(unit normal)). A stage-level entry point, used by the
    /// stage-by-stage tests against the CPU twin; the full backward builds on it.
    pub fn compose_bwd(
        &self,
        frame: &Frame,
        grads: &LayerGrads,
    ) -> Result<Vec<[f32; 4]>, GpuError> {
        let ctx = &self.ctx;
        let s = Stage { ctx, kernels: &self.kernels };
        let (Some(grid), Some(layers), Some(rays)) =
            (frame.grid(), frame.layer_buffers(), frame.rays())
        else {
            return Ok(Vec::new());
        };
        let scopes = gpu::ErrorScopes::open(ctx, "the adjoint of compose");
        let planes = frame.plane_count();
        let acc = gpu::storage(
            ctx,
            "trgs.compose_bwd.plane_grads",
            (planes.max(1) as u64) * PLANE_GRAD_FLOATS * 4,
        );
        let mut rec = Recorder::new(ctx, "trgs.compose_bwd", false);
        rec.encoder.clear_buffer(&acc, 0, None);
        compose_bwd::record(s, &mut rec, &grid, rays, layers, grads, &acc);
        let flat =
            rec.submit_and_wait(ctx).and_then(|()| gpu::read_buffer(ctx, &acc, 0, planes * 4));
        let flat: Vec<f32> = scopes.close_after(flat)?;
        Ok(flat.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect())
    }
}
