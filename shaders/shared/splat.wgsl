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

// What the adjoint passes need of the same evaluation: (alpha, G, 1 when o G is below the cap,
// so that alpha depends on o and G), or alpha = -1 when skipped. Same arithmetic as alpha_at, so
// the forward's and the replay's skip decisions agree bit for bit.
fn alpha_terms(conic: vec4<f32>, d: vec2<f32>) -> vec3<f32> {
    let power = -0.5 * (conic.x * d.x * d.x + conic.z * d.y * d.y) - conic.y * d.x * d.y;
    if !(power <= 0.0) {
        return vec3<f32>(-1.0, 0.0, 0.0);
    }
    let g = exp(power);
    let raw = conic.w * g;
    let alpha = min(MAX_ALPHA, raw);
    if !(alpha >= MIN_ALPHA) {
        return vec3<f32>(-1.0, 0.0, 0.0);
    }
    return vec3<f32>(alpha, g, select(0.0, 1.0, raw < MAX_ALPHA));
}

// The screen-space gradients that dL/dalpha of one Gaussian at one pixel gives its opacity, 2D
// mean and conic (twin: reference::rasterize_bwd::alpha_bwd), as the first two vec4 of its
// PROJECTED_GRAD_FLOATS record: (dmean2d, dopacity, 0) and (dconic a b c, 0). `terms` comes from
// alpha_terms; alpha = o G with G = exp(-(a dx^2 + c dy^2) / 2 - b dx dy), (dx, dy) = d.
fn alpha_bwd(conic: vec4<f32>, d: vec2<f32>, terms: vec3<f32>, g_alpha: f32) -> array<vec4<f32>, 2> {
    var out: array<vec4<f32>, 2>;
    if terms.z == 0.0 {
        return out; // alpha sits at its cap: flat in o and G
    }
    let g_power = g_alpha * conic.w * terms.y;
    out[0] = vec4<f32>(
        g_power * (conic.x * d.x + conic.y * d.y),
        g_power * (conic.y * d.x + conic.z * d.y),
        g_alpha * terms.y,
        0.0,
    );
    out[1] = vec4<f32>(-0.5 * g_power * d.x * d.x, -g_power * d.x * d.y, -0.5 * g_power * d.y * d.y, 0.0);
    return out;
}
