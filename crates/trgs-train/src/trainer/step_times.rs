//! Wall-clock milliseconds of each phase of a training step.

/// Wall-clock milliseconds of each phase of a step. With [`super::Trainer::time_phases`] (or
/// profiling) every phase ends with the GPU idle, so each holds its GPU work and the phases add
/// up to the step; otherwise the first four are the CPU's time recording them (nothing waits)
/// and the GPU's time shows in `readback`.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StepTimes {
    /// Forward render of every pass.
    pub render: f64,
    /// The image loss and the regularisers (GPU), and the readback of their values.
    pub loss: f64,
    /// The adjoint passes and the plane-gradient readback.
    pub backward: f64,
    /// Adam on the Gaussians and the densification statistics (GPU).
    pub adam: f64,
    /// Reading the step's loss, guard, key totals and plane gradients back (waiting for the
    /// GPU when they have not arrived), and Adam on the planes (CPU).
    #[serde(default)]
    pub readback: f64,
    /// Densification, pruning, opacity reset and perturbation, when their schedules run them.
    pub densify: f64,
}

impl StepTimes {
    pub fn total(&self) -> f64 {
        self.render + self.loss + self.backward + self.adam + self.readback + self.densify
    }

    /// The phases as (name, ms) pairs, for logs and reports.
    pub fn phases(&self) -> [(&'static str, f64); 6] {
        [
            ("render", self.render),
            ("loss", self.loss),
            ("backward", self.backward),
            ("adam", self.adam),
            ("readback", self.readback),
            ("densify", self.densify),
        ]
    }

    /// Add `other` phase by phase (for averages over a run).
    pub fn accumulate(&mut self, other: &StepTimes) {
        self.render += other.render;
        self.loss += other.loss;
        self.backward += other.backward;
        self.adam += other.adam;
        self.readback += other.readback;
        self.densify += other.densify;
    }
}
