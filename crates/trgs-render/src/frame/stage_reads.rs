//! What a rendered frame gives the kernels and tests that continue from its stages
//! ([`FrameStages`]): its views and layer buffers, pass 1's pixel states, each view's projected
//! records, and the geometry stages' results in the CPU twin's form.
use super::intermediates::{DepthOrderIntermediates, ViewIntermediates};
use super::{Frame, LayerBuffers, ViewBuffers};
use crate::GpuContext;
use crate::gpu::{self, GpuError};
use crate::layout::{ProjectedGaussian, RasterState};
use crate::toolkit::FrameStages;

impl FrameStages for Frame {
    fn views(&self) -> &[ViewBuffers] {
        &self.views
    }

    fn layer_buffers(&self) -> Option<&LayerBuffers> {
        self.layers.as_ref()
    }

    fn read_states(&self, ctx: &GpuContext) -> Result<Vec<RasterState>, GpuError> {
        self.layers
            .as_ref()
            .map_or_else(|| Ok(Vec::new()), |l| gpu::read_buffer(ctx, &l.states, 0, self.pixels()))
    }

    fn read_projected(
        &self,
        ctx: &GpuContext,
        vi: usize,
    ) -> Result<Option<Vec<ProjectedGaussian>>, GpuError> {
        let Some(v) = self.views.get(vi) else {
            return Ok(None);
        };
        v.projected.read(ctx).map(Some)
    }

    fn read_intermediates(
        &self,
        ctx: &GpuContext,
        vi: usize,
        gaussians: usize,
    ) -> Result<Option<ViewIntermediates>, GpuError> {
        self.intermediates_of(ctx, vi, gaussians)
    }

    fn read_depth_order(
        &self,
        ctx: &GpuContext,
    ) -> Result<Option<DepthOrderIntermediates>, GpuError> {
        self.depth_order_of(ctx)
    }
}

impl Frame {
    /// The geometry stages' results of view `vi` (0 = camera, then mirrored passes), in the
    /// twin's form of one view alone: its slice of the shared key list, with tile indices of the
    /// whole grid and ranges counted from the slice's start.
    fn intermediates_of(
        &self,
        ctx: &GpuContext,
        vi: usize,
        gaussians: usize,
    ) -> Result<Option<ViewIntermediates>, GpuError> {
        let (Some(v), Some(grid), Some(binning)) =
            (self.views.get(vi), self.grid, self.binning.as_ref())
        else {
            return Ok(None);
        };
        let (Some(keys), Some(view_ranges)) = (v.keys.as_ref(), v.ranges.as_ref()) else {
            return Ok(None);
        };
        let (sorted, sorted_values) = (
            keys.keys.read_range::<u32>(ctx, v.key_base, v.num_keys)?,
            keys.values.read_range::<u32>(ctx, v.key_base, v.num_keys)?,
        );
        let sorted_keys = sorted.iter().map(|&t| v.grid_tile(&grid, t)).collect();
        let own = v.tile_base..v.tile_base + v.limit.count();
        // The emitted list interleaves the views: this view's keys are those in its tiles.
        let emitted = match binning.emitted.as_ref() {
            None => None,
            Some(k) => {
                let tiles: Vec<u32> = k.keys.read_range(ctx, 0, binning.total)?;
                let values: Vec<u32> = k.values.read_range(ctx, 0, binning.total)?;
                Some(
                    tiles
                        .into_iter()
                        .zip(values)
                        .filter(|(t, _)| own.contains(t))
                        .map(|(t, value)| (v.grid_tile(&grid, t), value))
                        .unzip(),
                )
            }
        };
        let entries: Vec<u32> = binning.order.values.read_range(ctx, 0, binning.entries)?;
        let first = vi as u32 * self.gaussian_count;
        let order = entries
            .into_iter()
            .filter(|e| (first..first + self.gaussian_count).contains(e))
            .map(|e| e - first)
            .collect();
        let mut ranges = vec![(0, 0); grid.tile_count() as usize];
        let read: Vec<[u32; 2]> = gpu::read_buffer(
            ctx,
            view_ranges,
            u64::from(v.tile_base) * 8,
            v.limit.count() as usize,
        )?;
        for (local, [a, b]) in read.into_iter().enumerate() {
            if b > a {
                let tile = v.grid_tile(&grid, v.tile_base + local as u32) as usize;
                ranges[tile] = (a - v.key_base, b - v.key_base);
            }
        }
        Ok(Some(ViewIntermediates {
            projected: {
                let mut records = v.projected.read(ctx)?;
                records.truncate(gaussians);
                records
            },
            counts: gpu::read_buffer(ctx, &v.counts, 0, gaussians)?,
            order,
            emitted,
            sorted_keys,
            sorted_values,
            ranges,
        }))
    }

    /// The frame's depth order, every view's together.
    fn depth_order_of(
        &self,
        ctx: &GpuContext,
    ) -> Result<Option<DepthOrderIntermediates>, GpuError> {
        let Some(b) = self.binning.as_ref() else {
            return Ok(None);
        };
        let n = b.entries as usize;
        Ok(Some(DepthOrderIntermediates {
            entries: b.order.values.read_range(ctx, 0, b.entries)?,
            depths: b.order.keys.read_range(ctx, 0, b.entries)?,
            offsets: gpu::read_buffer(ctx, &b.offsets, 0, n)?,
            total: b.total,
        }))
    }
}
