//! Stage `adam`: one Adam step (Kingma and Ba, with bias correction, as 3DGS uses it) over a flat
//! array of parameters, in f64. The GPU stage (shaders/adam.wgsl) runs the same arithmetic in f32
//! on each attribute buffer of a scene.

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

/// Step `t` (1-based) of Adam with learning rates `rate`: updates the moments `m`, `v` and the
/// parameters in place. All four slices have the same length.
pub fn adam(
    params: &mut [f64],
    grads: &[f64],
    m: &mut [f64],
    v: &mut [f64],
    rate: &AdamRate,
    t: u32,
    s: &AdamSettings,
) {
    let (b1, b2) = s.bias_corrections(t);
    for i in 0..params.len() {
        let lr = rate.at(i);
        let g = grads[i];
        m[i] = s.beta1 * m[i] + (1.0 - s.beta1) * g;
        v[i] = s.beta2 * v[i] + (1.0 - s.beta2) * g * g;
        params[i] -= lr * (m[i] / b1) / ((v[i] / b2).sqrt() + s.eps);
    }
}
