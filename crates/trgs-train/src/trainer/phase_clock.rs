//! Wall-clock laps of a training step's phases.
use trgs_render::{GpuContext, GpuError};

/// Laps of wall-clock time that wait for the GPU to go idle first, so that work submitted in
/// one phase is not billed to the next.
pub(super) struct PhaseClock {
    last: std::time::Instant,
}

impl PhaseClock {
    pub(super) fn start() -> Self {
        Self { last: std::time::Instant::now() }
    }

    /// Milliseconds since the previous lap.
    pub(super) fn lap(&mut self, ctx: &GpuContext) -> Result<f64, GpuError> {
        trgs_render::toolkit::gpu::wait_for_gpu(ctx, "a training phase")?;
        let now = std::time::Instant::now();
        let ms = 1e3 * (now - self.last).as_secs_f64();
        self.last = now;
        Ok(ms)
    }
}
