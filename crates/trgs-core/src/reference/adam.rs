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

/// Step `t` (1-based) of Adam with learning rate `lr`: updates the moments `m`, `v` and the
/// parameters in place. All four slices have the same length.
pub fn adam(
    params: &mut [f64],
    grads: &[f64],
    m: &mut [f64],
    v: &mut [f64],
    lr: f64,
    t: u32,
    s: &AdamSettings,
) {
    let (b1, b2) = s.bias_corrections(t);
    for i in 0..params.len() {
        let g = grads[i];
        m[i] = s.beta1 * m[i] + (1.0 - s.beta1) * g;
        v[i] = s.beta2 * v[i] + (1.0 - s.beta2) * g * g;
        params[i] -= lr * (m[i] / b1) / ((v[i] / b2).sqrt() + s.eps);
    }
}
