//! Adam's settings and per-float learning rates, which stage `adam` on the GPU, the planes' Adam
//! on the CPU and the twin all step with.

/// Adam's constants (3DGS: beta1 0.9, beta2 0.999, eps 1e-15).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdamSettings {
    pub beta1: f64,
    pub beta2: f64,
    pub eps: f64,
}

impl Default for AdamSettings {
    fn default() -> Self {
        Self { beta1: 0.9, beta2: 0.999, eps: 1e-15 }
    }
}

impl AdamSettings {
    /// The bias corrections (1 - beta1^t, 1 - beta2^t) of step `t` (1-based).
    pub fn bias_corrections(&self, t: u32) -> (f64, f64) {
        let t = i32::try_from(t).unwrap_or(i32::MAX);
        (1.0 - self.beta1.powi(t), 1.0 - self.beta2.powi(t))
    }
}

/// The learning rate of each float of an attribute buffer: `lr`, except the first `lead` floats
/// of every record of `stride` floats (stride 0: none), which take `lead_lr`. 3DGS steps the SH
/// DC colour 20 times faster than the higher bands; both live in one buffer here.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdamRate {
    pub lr: f64,
    pub lead_lr: f64,
    pub lead: u32,
    pub stride: u32,
}

impl AdamRate {
    /// The same rate for every float.
    pub fn uniform(lr: f64) -> Self {
        Self { lr, lead_lr: lr, lead: 0, stride: 0 }
    }

    /// The rate of float `i` of the buffer.
    pub fn at(&self, i: usize) -> f64 {
        if self.stride != 0 && (i % self.stride as usize) < self.lead as usize {
            self.lead_lr
        } else {
            self.lr
        }
    }
}
