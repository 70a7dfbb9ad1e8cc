//! Stage `emit_keys` (shaders/emit_keys.wgsl; twin `trgs_core::reference::emit_keys`).
use super::Stage;
use super::project::{Candidates, WORK_STRIDE};
use crate::gpu::{self, Recorder, range};
use crate::layout::{ProjectedGaussian, TileParams};
use crate::scene::GpuScene;

const PROJECTED: u64 = std::mem::size_of::<ProjectedGaussian>() as u64;

/// The split 64-bit keys (tile, depth bits) and their values (Gaussian indices).
#[derive(Clone, Debug)]
pub struct Keys {
    pub hi: wgpu::Buffer,
    pub lo: wgpu::Buffer,
    pub values: wgpu::Buffer,
}

pub fn record(
    s: Stage<'_>,
    rec: &mut Recorder,
    scene: &GpuScene,
    base: &TileParams,
    projected: &wgpu::Buffer,
    candidates: &Candidates,
    offsets: &wgpu::Buffer,
    keys: &Keys,
) {
    let k = &s.kernels.emit_keys;
    for (chunk, (first, count)) in scene.chunks().into_iter().enumerate() {
        let [list, work] = candidates.chunk(chunk, first, count);
        let p = TileParams { count, first, ..*base };
        let block = gpu::params(s.ctx, "trgs.emit_keys.params", &p);
        let (f, c) = (u64::from(first), u64::from(count));
        let bind = k.bind(
            s.ctx,
            &[
                block.as_entire_binding(),
                range(projected, f * PROJECTED, c * PROJECTED),
                range(offsets, f * 4, c * 4),
                keys.hi.as_entire_binding(),
                keys.lo.as_entire_binding(),
                keys.values.as_entire_binding(),
                list,
                work,
            ],
        );
        let at = chunk as u64 * WORK_STRIDE;
        rec.dispatch_indirect("emit_keys", k, &bind, &candidates.work, at);
    }
}
