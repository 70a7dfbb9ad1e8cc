//! Phase 1 of a render: for every view, project and count tiles (the touching Gaussians become
//! entries of the frame's depth order); list and sort the entries by depth, scan their tile
//! counts in that order; then one readback of the totals.
use super::checks::PROJECTED_BYTES;
use super::job::{RenderJob, ViewSpec};
use crate::frame::{ViewBuffers, key_totals};
use crate::gpu::{self, BufferPool, Recorder};
use crate::layout::TileParams;
use crate::stages::depth_order::DepthOrder;
use crate::stages::tile_counts::DepthEntries;
use crate::stages::{ItemCount, depth_order, prefix_sum, project, tile_counts};
use crate::toolkit::paged::Paged;

/// The depth order of every view's entries, which phase 2 emits the keys from.
#[derive(Debug)]
pub(super) struct DepthBinning {
    pub entries: DepthEntries,
    pub order: DepthOrder,
    /// The entries' tile counts in depth order, scanned into their first key slots.
    pub offsets: wgpu::Buffer,
    /// The scan's total (its first u32): the keys of every view.
    pub total: wgpu::Buffer,
}

/// The copy of the key totals that sizes the key list: read back halfway through the render,
/// or after it.
#[derive(Debug)]
pub(super) struct TotalsCopy {
    pub staging: wgpu::Buffer,
    /// u32 words in `staging` ([`key_totals::words`]).
    pub words: usize,
}

/// What phase 1 leaves: each view's geometry buffers, the depth order and the totals' copy.
#[derive(Debug)]
pub(super) struct Binned {
    pub views: Vec<ViewBuffers>,
    pub depth: DepthBinning,
    pub totals: TotalsCopy,
}

/// Records phase 1 (the module's docs) for the views `specs`.
pub(super) fn bin_views(
    rec: &mut Recorder,
    pool: &mut BufferPool,
    job: &RenderJob<'_>,
    specs: &[ViewSpec],
) -> Binned {
    let entries = DepthEntries::new(job.s, rec, pool, specs.len(), job.scene.len());
    let views = project_views(rec, pool, job, specs, &entries);
    let depth = order_entries(rec, pool, job, entries);
    let totals = copy_totals(rec, job, &depth, specs.len());
    Binned { views, depth, totals }
}

/// Projects every view's Gaussians (the cheap culls of all views first, in one pass over the
/// scene) and counts the tiles each touches, marking the entries of the depth order.
fn project_views(
    rec: &mut Recorder,
    pool: &mut BufferPool,
    job: &RenderJob<'_>,
    specs: &[ViewSpec],
    entries: &DepthEntries,
) -> Vec<ViewBuffers> {
    let (s, ctx, scene, options) = (job.s, job.s.ctx, job.scene, job.options);
    let (k, planes, n) = (&job.camera.intrinsics, scene.planes(), u64::from(scene.len()));
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
    project::record_candidates(s, rec, scene, &view_params, &candidates, &projected);
    let each = view_params.into_iter().zip(projected).zip(candidates);
    for (vi, (spec, ((pparams, projected), candidates))) in specs.iter().zip(each).enumerate() {
        let counts = pool.get(ctx, &format!("trgs.tile_counts.counts.v{vi}"), n * 4);
        project::record(s, rec, scene, &pparams, &candidates, &projected);
        let tparams = TileParams {
            entry_base: vi as u32 * scene.len(),
            view: vi as u32,
            ..tile_counts::params(&job.grid, &spec.limit, options.near)
        };
        let c = &candidates;
        tile_counts::record(s, rec, scene, &tparams, &projected, c, &counts, entries);
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
    views
}

/// Lists the present entries in depth order and scans their tile counts.
fn order_entries(
    rec: &mut Recorder,
    pool: &mut BufferPool,
    job: &RenderJob<'_>,
    entries: DepthEntries,
) -> DepthBinning {
    let (s, ctx) = (job.s, job.s.ctx);
    // The entries' tile counts in depth order, scanned in place into their first key slots.
    let offsets = pool.get(ctx, "trgs.depth_order.offsets", u64::from(entries.capacity) * 4);
    let order = depth_order::record(s, rec, pool, &entries, &offsets);
    let in_order = ItemCount::OnGpu { counter: &order.entries, capacity: entries.capacity };
    let total =
        prefix_sum::record(s, rec, "prefix_sum", pool, "trgs.prefix_sum", &offsets, in_order);
    DepthBinning { entries, order, offsets, total }
}

/// Copies the key totals of `views` views (the entries listed, each view's keys, the scan's
/// total) into one staging buffer.
fn copy_totals(
    rec: &mut Recorder,
    job: &RenderJob<'_>,
    depth: &DepthBinning,
    views: usize,
) -> TotalsCopy {
    let words = key_totals::words(views);
    let staging = gpu::staging(job.s.ctx, "trgs.prefix_sum.totals", 4 * words as u64);
    let views_bytes = 8 * views as u64;
    let view_totals = &depth.entries.key_totals;
    rec.encoder.copy_buffer_to_buffer(&depth.order.entries, 0, &staging, 0, 4);
    rec.encoder.copy_buffer_to_buffer(view_totals, 0, &staging, 4, views_bytes);
    rec.encoder.copy_buffer_to_buffer(&depth.total, 0, &staging, 4 + views_bytes, 4);
    TotalsCopy { staging, words }
}
