//! The forward renderer: the stages of the data flow (docs/ARCHITECTURE.md) for one camera, into
//! a [`Frame`].
use crate::GpuContext;
use crate::frame::key_totals;
use crate::frame::{Binning, Frame, KeySizing, KeyTotals, ViewBuffers};
use crate::gpu::{self, GpuError, PendingRead, Recorder};
use crate::kernels::Kernels;
use crate::layer_grads::LayerGrads;
use crate::layout::{EmitParams, TileParams, ViewTiles};
use crate::scene::GpuScene;
use crate::stages::ItemCount;
use crate::stages::compose_bwd;
use crate::stages::rasterize::Pass1Outputs;
use crate::stages::sort::KeyList;
use crate::stages::tile_counts::DepthEntries;
use crate::stages::{
    Stage, compose, depth_order, emit_keys, prefix_sum, project, rasterize, rasterize_reflection,
    sort, tile_counts, tile_ranges,
};
use crate::toolkit::FrameStages;
use crate::toolkit::paged::{MAX_PAGES, Paged};
use trgs_core::plane_math::mirrored_view;
use trgs_core::reference::ReflectionModel;
use trgs_core::reference::{TileGrid, footprint};
use trgs_core::scene::{Camera, CameraError, InvalidInput, ViewTransform};

/// How to render.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Colour behind the last transmittance of C_t.
    pub background: [f32; 3],
    /// Gaussians with a camera-space depth below this are culled (0.2 as in 3DGS).
    pub near: f64,
    /// Compute the depth-variance layer V (a second walk over each pixel's Gaussians; only the
    /// depth-variance loss needs it).
    pub depth_variance: bool,
    /// Per-plane switch (missing entries are on): a disabled plane gets no mirrored pass and no
    /// hit, as if it were not in the scene.
    pub enabled_planes: Vec<bool>,
    /// Time every stage with timestamp queries when the adapter has them ([`Frame::stage_times`]).
    pub profile: bool,
    /// Evaluate SH only up to this degree (training's degree schedule); None or a larger value
    /// uses the scene's. The backward of the frame follows the same degree.
    pub sh_degree: Option<u32>,
    /// Keep copies of the tile counts and the unsorted keys (stage-by-stage tests).
    pub capture_intermediates: bool,
    /// Parts of the reflection model (Schlick, the intensity map A) switched off for ablations;
    /// the backward of the frame follows the same model.
    pub reflection: ReflectionModel,
    /// How the frame's key list is sized: exactly, waiting for the binning's totals halfway
    /// through the render, or from earlier frames without waiting ([`KeySizing`]).
    pub key_sizing: KeySizing,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            background: [0.0; 3],
            near: 0.2,
            depth_variance: false,
            enabled_planes: Vec::new(),
            profile: false,
            sh_degree: None,
            capture_intermediates: false,
            reflection: ReflectionModel::default(),
            key_sizing: KeySizing::Exact,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(transparent)]
    Input(#[from] InvalidInput),
    #[error("camera {name:?}: {source}")]
    Camera { name: String, source: CameraError },
    #[error("camera {name:?}: image size {width}x{height} must be at least 1x1")]
    EmptyImage { name: String, width: u32, height: u32 },
    /// One of the frame's buffers would exceed what the adapter can bind at once.
    #[error(
        "camera {name:?}: the frame's {what} need {bytes} bytes in one binding, over the \
         adapter's limit of {limit} bytes; render at a lower resolution or with fewer Gaussians"
    )]
    FrameTooLarge { name: String, what: &'static str, bytes: u64, limit: u64 },
    /// The image needs more tiles along one axis than a dispatch can have workgroups.
    #[error(
        "camera {name:?}: {tiles} tiles along one image axis, over the adapter's limit of {limit} \
         workgroups per dispatch dimension; render at a lower resolution"
    )]
    TooManyTiles { name: String, tiles: u32, limit: u32 },
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

/// The largest per-pixel buffer of a frame with `planes` reflection slots, in bytes per pixel
/// (the layers are bound whole, unlike the scene's attributes, which are bound in chunks).
fn bytes_per_pixel(planes: usize) -> u64 {
    let slots = planes.max(1) as u64;
    let state = std::mem::size_of::<crate::layout::RasterState>() as u64;
    let reflection =
        slots * (16u64).max(std::mem::size_of::<crate::layout::ReflectionState>() as u64);
    state.max(16).max(reflection)
}

/// Bytes of one projected Gaussian's record.
const PROJECTED_BYTES: u64 = std::mem::size_of::<crate::layout::ProjectedGaussian>() as u64;

/// Fails when a buffer of `bytes` would not fit one binding.
fn check_binding(
    ctx: &GpuContext,
    camera: &Camera,
    what: &'static str,
    bytes: u64,
) -> Result<(), RenderError> {
    let limit = ctx.binding_limit();
    if bytes > limit {
        return Err(RenderError::FrameTooLarge { name: camera.name.clone(), what, bytes, limit });
    }
    Ok(())
}

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

/// One view to project and bin: the real camera, or the camera mirrored about plane `plane`.
struct ViewSpec {
    view: ViewTransform,
    plane: Option<usize>,
    limit: trgs_core::reference::TileRect,
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
    /// [`MAX_PAGES`] pages of keys.
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

    fn render_scoped(
        &self,
        scene: &GpuScene,
        camera: &Camera,
        options: &RenderOptions,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        let ctx = &self.ctx;
        let k = &camera.intrinsics;
        if k.width == 0 || k.height == 0 {
            return Err(RenderError::EmptyImage {
                name: camera.name.clone(),
                width: k.width,
                height: k.height,
            });
        }
        camera
            .validate()
            .map_err(|source| RenderError::Camera { name: camera.name.clone(), source })?;
        let background = options.background.map(f64::from);
        trgs_core::reference::check_render_settings(background, options.near)?;
        let s = Stage { ctx, kernels: &self.kernels };
        let grid = TileGrid::new(k.width, k.height);
        let most = ctx.device.limits().max_compute_workgroups_per_dimension;
        if let Some(tiles) = [grid.tiles_x, grid.tiles_y].into_iter().find(|&t| t > most) {
            return Err(RenderError::TooManyTiles {
                name: camera.name.clone(),
                tiles,
                limit: most,
            });
        }
        let pixels = u64::from(k.width) * u64::from(k.height);
        let view = ViewTransform::from(&camera.pose);
        let planes = scene.planes();
        check_binding(ctx, camera, "image layers", pixels * bytes_per_pixel(planes.len()))?;
        // The rasterize passes bind each view's projected Gaussians whole, in at most MAX_PAGES
        // pages of one binding each.
        let pages = scene.len().div_ceil(scene.page_len());
        if pages > MAX_PAGES {
            return Err(RenderError::FrameTooLarge {
                name: camera.name.clone(),
                what: "projected Gaussians (one record each, in two bindings)",
                bytes: u64::from(scene.len()) * PROJECTED_BYTES,
                limit: u64::from(MAX_PAGES * scene.page_len()) * PROJECTED_BYTES,
            });
        }
        let mut specs = vec![ViewSpec { view, plane: None, limit: grid.full() }];
        for (i, plane) in planes.iter().enumerate() {
            if !options.enabled_planes.get(i).copied().unwrap_or(true) {
                continue;
            }
            if let Some(fp) = footprint(plane, &camera.pose, k, &grid) {
                specs.push(ViewSpec {
                    view: mirrored_view(plane, &view),
                    plane: Some(i),
                    limit: fp,
                });
            }
        }
        // The previous render's totals, if still on their way, size this one's key list.
        frame.settle_keys(ctx)?;
        frame.reset(grid, planes.len(), scene.len(), options);
        // Over two bindings, or a u32 total that would have wrapped.
        let most_keys = (u64::from(MAX_PAGES) * u64::from(self.key_page_len)).min(u32::MAX.into());
        let estimate = match options.key_sizing {
            KeySizing::FromEarlierFrames if !options.capture_intermediates => {
                frame.key_capacity(most_keys)
            }
            _ => None,
        };
        // Entry indices (view x Gaussian) are u32 (the key totals carry, see tile_counts).
        let capacity = specs.len() as u64 * u64::from(scene.len());
        if capacity > u64::from(u32::MAX) {
            return Err(RenderError::FrameTooLarge {
                name: camera.name.clone(),
                what: "depth-order entries (views x Gaussians)",
                bytes: capacity * 4,
                limit: u64::from(u32::MAX) * 4,
            });
        }
        check_binding(ctx, camera, "depth-order tile rectangles", capacity * 8)?;
        let pool = &mut frame.pool;
        let n = u64::from(scene.len());
        let mut rec = Recorder::new(ctx, "trgs.render", options.profile);

        // Phase 1: for every view, project and count tiles (the touching Gaussians become entries
        // of the frame's depth order); list and sort the entries by depth, scan their tile
        // counts in that order; then one readback of the totals.
        let entries = DepthEntries::new(s, &mut rec, pool, specs.len(), scene.len());
        let sh_degree = options.sh_degree.map_or(scene.sh_degree(), |d| d.min(scene.sh_degree()));
        let mut views = Vec::with_capacity(specs.len());
        let view_params: Vec<_> = specs
            .iter()
            .map(|spec| {
                let plane = spec.plane.map(|p| &planes[p]);
                project::params(&spec.view, k, plane, &spec.limit, options.near, sh_degree)
            })
            .collect();
        let projected: Vec<_> = (0..specs.len())
            .map(|vi| {
                let label = format!("trgs.project.projected.v{vi}");
                Paged::from_pool(ctx, pool, &label, scene.len(), scene.page_len(), PROJECTED_BYTES)
            })
            .collect();
        let candidates: Vec<_> =
            (0..specs.len()).map(|vi| project::Candidates::new(s, pool, scene, vi)).collect();
        project::record_candidates(s, &mut rec, scene, &view_params, &candidates, &projected);
        let each = view_params.into_iter().zip(projected).zip(candidates);
        for (vi, (spec, ((pparams, projected), candidates))) in specs.iter().zip(each).enumerate() {
            let counts = pool.get(ctx, &format!("trgs.tile_counts.counts.v{vi}"), n * 4);
            project::record(s, &mut rec, scene, &pparams, &candidates, &projected);
            let tparams = TileParams {
                entry_base: vi as u32 * scene.len(),
                view: vi as u32,
                ..tile_counts::params(&grid, &spec.limit, options.near)
            };
            let c = &candidates;
            tile_counts::record(s, &mut rec, scene, &tparams, &projected, c, &counts, &entries);
            views.push(ViewBuffers {
                view: spec.view,
                plane: spec.plane,
                limit: spec.limit,
                project_params: pparams,
                projected,
                candidates,
                counts,
                keys: None,
                ranges: None,
                num_keys: 0,
                key_base: 0,
                tile_base: 0,
            });
        }
        // The entries' tile counts in depth order, scanned in place into their first key slots.
        let offsets = pool.get(ctx, "trgs.depth_order.offsets", u64::from(entries.capacity) * 4);
        let order = depth_order::record(s, &mut rec, pool, &entries, &offsets);
        let in_order = ItemCount::OnGpu { counter: &order.entries, capacity: entries.capacity };
        let total = prefix_sum::record(
            s,
            &mut rec,
            "prefix_sum",
            pool,
            "trgs.prefix_sum",
            &offsets,
            in_order,
        );
        let words = key_totals::words(specs.len());
        let totals_staging = gpu::staging(ctx, "trgs.prefix_sum.totals", 4 * words as u64);
        let views_bytes = 8 * specs.len() as u64;
        rec.encoder.copy_buffer_to_buffer(&order.entries, 0, &totals_staging, 0, 4);
        rec.encoder.copy_buffer_to_buffer(&entries.key_totals, 0, &totals_staging, 4, views_bytes);
        rec.encoder.copy_buffer_to_buffer(&total, 0, &totals_staging, 4 + views_bytes, 4);
        // The key list: sized exactly from the totals read back now, or from earlier frames with
        // the counts left on the GPU (emit_keys drops what the list cannot hold).
        let (capacity, exact) = match estimate {
            Some(capacity) => (capacity, None),
            None => {
                rec.submit_and_wait(ctx)?;
                let words: Vec<u32> = gpu::map_and_read(ctx, &totals_staging, 4 * words)?;
                let totals = key_totals::Totals::decode(&words);
                let all_keys = totals.keys();
                debug_assert!(
                    all_keys > most_keys || all_keys == u64::from(words[words.len() - 1]),
                    "the views' key totals add up to the scan's"
                );
                // Checked before the u32 scan's total is trusted: a frame of 2^32 keys or more
                // is over two bindings of any adapter's, and its total would have wrapped.
                if all_keys > most_keys {
                    return Err(RenderError::FrameTooLarge {
                        name: camera.name.clone(),
                        what: "tile keys (all views together, in two bindings)",
                        bytes: all_keys * 4,
                        limit: most_keys * 4,
                    });
                }
                key_totals::assign(&mut views, &totals.view_keys);
                // Below 2^32: checked above against a binding limit of at most 4 GiB.
                (all_keys as u32, Some(totals))
            }
        };

        // Phase 2: every view's keys into one list (a view's tiles numbered after the previous
        // view's: the camera's whole grid, then each footprint), one sort by tile, one pass of
        // tile ranges; both rasterize passes; compose.
        let mut tile_base = 0u32;
        let mut tables = Vec::with_capacity(views.len());
        for v in &mut views {
            v.tile_base = tile_base;
            tables.push(ViewTiles {
                tile_base,
                x0: v.limit.x0,
                y0: v.limit.y0,
                row: v.limit.x1 - v.limit.x0,
            });
            tile_base += v.limit.count();
        }
        let tiles = tile_base;
        let keys = KeyList::from_pool(ctx, pool, "trgs.emit_keys", capacity, self.key_page_len);
        let kept = pool.get(ctx, "trgs.emit_keys.kept", 8);
        let (in_order, held) = match &exact {
            Some(t) => (ItemCount::Known(t.entries), ItemCount::Known(capacity)),
            None => (
                ItemCount::OnGpu { counter: &order.entries, capacity: entries.capacity },
                ItemCount::OnGpu { counter: &kept, capacity },
            ),
        };
        let emit = EmitParams { gaussians: scene.len(), ..Default::default() };
        let o = &order.list.values;
        let counts = emit_keys::KeyCounts { total: &total, kept: &kept };
        let offs = &offsets;
        emit_keys::record(
            s, &mut rec, &emit, in_order, capacity, o, &entries, offs, &tables, &keys, &counts,
        );
        let captured_keys = options.capture_intermediates.then(|| {
            let copy = KeyList::from_pool(ctx, pool, "trgs.capture", capacity, self.key_page_len);
            for (from, to) in [(&keys.keys, &copy.keys), (&keys.values, &copy.values)] {
                for (src, dst) in from.pages().iter().zip(to.pages()) {
                    rec.encoder.copy_buffer_to_buffer(src, 0, dst, 0, src.size().min(dst.size()));
                }
            }
            copy
        });
        let tile_digits: Vec<_> = sort::digits(sort::bits_below(tiles)).collect();
        let sorted =
            sort::record(s, &mut rec, "sort", pool, "trgs.sort", &keys, held, &tile_digits);
        let ranges = pool.get(ctx, "trgs.tile_ranges.ranges", u64::from(tiles) * 8);
        tile_ranges::record(s, &mut rec, &sorted.keys, held, &ranges);
        for v in &mut views {
            v.keys = Some(sorted.clone());
            v.ranges = Some(ranges.clone());
        }
        let binning = Binning {
            order: order.list,
            offsets,
            // A list sized from earlier frames learns these when its totals arrive.
            entries: exact.as_ref().map_or(0, |t| t.entries),
            total: if exact.is_some() { capacity } else { 0 },
            emitted: captured_keys,
            kept: kept.clone(),
        };
        let layers = frame.layers(ctx, pixels);
        let primary = &views[0];
        #[allow(clippy::expect_used)]
        let (p_values, p_ranges) = (
            &primary.keys.as_ref().expect("sorted above").values,
            primary.ranges.as_ref().expect("set above"),
        );
        rasterize::record(
            s,
            &mut rec,
            &grid,
            options.background,
            options.depth_variance,
            &primary.projected,
            p_values,
            p_ranges,
            &Pass1Outputs {
                transmission: &layers.transmission,
                geometry: &layers.geometry,
                states: &layers.states,
            },
        );
        let mut has_pass = vec![false; planes.len()];
        for v in &views[1..] {
            has_pass[v.plane.unwrap_or(0)] = true;
        }
        let rays = compose::RayBuffers::new(
            s,
            camera,
            &compose::planes_gpu(planes, &has_pass),
            options.reflection,
        );
        if views.len() == 1 {
            // No plane hit anywhere: H = 0, which compose_bwd reads.
            rec.encoder.clear_buffer(&layers.hit, 0, None);
        } else {
            let r = &rays;
            rec.encoder.clear_buffer(&layers.reflection_raw, 0, None);
            rec.encoder.clear_buffer(&layers.reflection_states, 0, None);
            for v in &views[1..] {
                #[allow(clippy::expect_used)]
                let (keys, ranges) =
                    (v.keys.as_ref().expect("sorted above"), v.ranges.as_ref().expect("set above"));
                let slot = v.plane.unwrap_or(0) as u32;
                rasterize_reflection::record(
                    s,
                    &mut rec,
                    &grid,
                    slot,
                    &v.limit,
                    v.tile_base,
                    &v.projected,
                    &keys.values,
                    ranges,
                    &layers.reflection_raw,
                    &layers.reflection_states,
                    r,
                );
            }
            let footprints: Vec<_> = views[1..].iter().map(|v| v.limit).collect();
            compose::record(
                s,
                &mut rec,
                &grid,
                &footprints,
                r,
                &layers.transmission,
                &layers.geometry,
                &layers.reflection_raw,
                &compose::ComposeOutputs {
                    color: &layers.color,
                    reflection: &layers.reflection,
                    strength: &layers.strength,
                    hit: &layers.hit,
                },
            );
        }
        let submission = if exact.is_some() {
            rec.submit_and_wait(ctx)?;
            None
        } else {
            Some(rec.submit(ctx)?)
        };
        frame.finish(views, binning, has_pass, Some(rays), &rec);
        match submission {
            None => {
                let keys = u64::from(capacity);
                frame.record_key_totals(KeyTotals { keys, capacity: keys });
            }
            Some(submission) => frame.expect_key_totals(key_totals::PendingKeyTotals::start(
                PendingRead::after(totals_staging, submission),
                words,
                u64::from(capacity),
                frame.renders(),
            )),
        }
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
            (planes.max(1) as u64) * compose_bwd::PLANE_GRAD_FLOATS * 4,
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
