//! Wall-clock laps of a training step's phases.
use trgs_render::{GpuContext, GpuError};

/// Laps of wall-clock time. With `wait` (profiling, or phase times asked for), each lap waits
/// for the GPU to go idle first, so that work submitted in one phase is not billed to the
/// next; without, a lap is the CPU's time recording the phase, and nothing waits.
pub(super) struct PhaseClock {
    start: std::time::Instant,
    last: std::time::Instant,
    wait: bool,
}

impl PhaseClock {
    pub(super) fn start(wait: bool) -> Self {
        let now = std::time::Instant::now();
        Self { start: now, last: now, wait }
    }

    /// Milliseconds since the previous lap.
    pub(super) fn lap(&mut self, ctx: &GpuContext) -> Result<f64, GpuError> {
        self.settle(ctx)?;
        let now = std::time::Instant::now();
        let ms = 1e3 * (now - self.last).as_secs_f64();
        self.last = now;
        Ok(ms)
    }

    /// Milliseconds since the start.
    pub(super) fn elapsed(&self, ctx: &GpuContext) -> Result<f64, GpuError> {
        self.settle(ctx)?;
        Ok(1e3 * self.start.elapsed().as_secs_f64())
    }

    fn settle(&self, ctx: &GpuContext) -> Result<(), GpuError> {
        if self.wait {
            trgs_render::toolkit::gpu::wait_for_gpu(ctx, "a training phase")?;
        }
        Ok(())
    }
}
