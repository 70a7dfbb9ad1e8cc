// Per-pixel evaluation of one projected Gaussian (twin: reference::rasterize::alpha_at).

// alpha = min(MAX_ALPHA, o G) at pixel offset d = pixel - mean, or -1 when the Gaussian is
// skipped (alpha < 1/255, or a non-decaying exponent from a numerically bad conic).
fn alpha_at(conic: vec4<f32>, d: vec2<f32>) -> f32 {
    let power = -0.5 * (conic.x * d.x * d.x + conic.z * d.y * d.y) - conic.y * d.x * d.y;
    if !(power <= 0.0) {
        return -1.0;
    }
    let alpha = min(MAX_ALPHA, conic.w * exp(power));
    if !(alpha >= MIN_ALPHA) {
        return -1.0;
    }
    return alpha;
}
