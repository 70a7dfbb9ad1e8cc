//! Readback of a frame's geometry stages, in the CPU twin's form (for stage-by-stage tests).
use super::Frame;
use crate::GpuContext;
use crate::gpu::{self, GpuError};
use crate::layout::ProjectedGaussian;

/// Intermediate results of one view's geometry stages (for stage-by-stage tests).
#[derive(Clone, Debug)]
pub struct ViewIntermediates {
    pub projected: Vec<ProjectedGaussian>,
    /// Tile counts per Gaussian.
    pub counts: Vec<u32>,
    /// This view's Gaussians in the frame's depth order.
    pub order: Vec<u32>,
    /// This view's keys (tile indices of the whole grid) and values as emitted, in emission
    /// order (with `capture_intermediates`).
    pub emitted: Option<(Vec<u32>, Vec<u32>)>,
    /// This view's sorted keys (tile indices of the whole grid) and values.
    pub sorted_keys: Vec<u32>,
    pub sorted_values: Vec<u32>,
    pub ranges: Vec<(u32, u32)>,
}

/// The frame's depth order, read back (for stage-by-stage tests).
#[derive(Clone, Debug)]
pub struct DepthOrderIntermediates {
    /// Entry indices (`view * Gaussians + index`), front to back.
    pub entries: Vec<u32>,
    /// Their depth bits.
    pub depths: Vec<u32>,
    /// The exclusive scan of their tile counts.
    pub offsets: Vec<u32>,
    /// Keys of all views.
    pub total: u32,
}

impl Frame {
    /// The geometry stages' results of view `vi` (0 = camera, then mirrored passes), in the
    /// twin's form of one view alone: its slice of the shared key list, with tile indices of the
    /// whole grid and ranges counted from the slice's start.
    pub(crate) fn intermediates_of(
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
    pub(crate) fn depth_order_of(
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
