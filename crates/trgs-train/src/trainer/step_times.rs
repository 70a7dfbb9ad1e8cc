//! Wall-clock milliseconds of each phase of a training step.

/// Wall-clock milliseconds of each phase of a step. Every phase ends with the GPU idle (the
/// step reads back between phases anyway), so the phases add up to the step.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StepTimes {
    /// Forward render of every pass.
    pub render: f64,
    /// The image loss and the regularisers (GPU), and the readback of their values.
    pub loss: f64,
    /// The adjoint passes and the plane-gradient readback.
    pub backward: f64,
    /// Adam on the Gaussians (GPU) and the planes (CPU), and the densification statistics.
    pub adam: f64,
    /// Densification, pruning, opacity reset and perturbation, when their schedules run them.
    pub densify: f64,
}

impl StepTimes {
    pub fn total(&self) -> f64 {
        self.render + self.loss + self.backward + self.adam + self.densify
    }

    /// The phases as (name, ms) pairs, for logs and reports.
    pub fn phases(&self) -> [(&'static str, f64); 5] {
        [
            ("render", self.render),
            ("loss", self.loss),
            ("backward", self.backward),
            ("adam", self.adam),
            ("densify", self.densify),
        ]
    }

    /// Add `other` phase by phase (for averages over a run).
    pub fn accumulate(&mut self, other: &StepTimes) {
        self.render += other.render;
        self.loss += other.loss;
        self.backward += other.backward;
        self.adam += other.adam;
        self.densify += other.densify;
    }
}
