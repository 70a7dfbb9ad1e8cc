//! Stage `adam`: one Adam step (Kingma and Ba, with bias correction, as 3DGS uses it) over a flat
//! array of parameters, in f64. The GPU stage (shaders/training/adam.wgsl) runs the same
//! arithmetic in f32 on each attribute buffer of a scene.
use crate::pipeline::{AdamRate, AdamSettings};

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
