// The cheap culls of stage `project` (twin: trgs_core::reference::project), shared by its two
// kernels: `project_candidates` runs them on every Gaussian and lists the survivors, `project`
// recomputes the same quantities for the listed ones only. Both shaders bind `view`, `means`,
// `log_scales`, `opacity_logits` and `populations` under these names.
//
// Why two kernels: CPU adapters (lavapipe) run a branch with every lane of a SIMD chunk masked
// off as if it were taken, so a culled Gaussian costs the full projection and SH evaluation
// unless it never reaches that code; a mirrored view culls most of the scene.

struct ViewPoint {
    mu: vec3<f32>,
    // Camera-space position.
    p: vec3<f32>,
    opacity: f32,
    // alpha = o G >= 1/255  <=>  the quadratic form is at most `reach` = 2 ln(255 o).
    reach: f32,
    log_s: vec3<f32>,
    glass: bool,
    // Tangents of the mean clamped to the guard band, and the screen-space mean.
    tx: f32,
    ty: f32,
    mean2d: vec2<f32>,
}

fn view_point(i: u32) -> ViewPoint {
    var v: ViewPoint;
    v.mu = vec3<f32>(means[3u * i], means[3u * i + 1u], means[3u * i + 2u]);
    v.glass = populations[i] == POPULATION_GLASS;
    let w = transpose(mat3x3<f32>(view.row0.xyz, view.row1.xyz, view.row2.xyz));
    v.p = w * v.mu + view.translation.xyz;
    v.opacity = sigmoid(opacity_logits[i]);
    v.reach = 2.0 * log(v.opacity / MIN_ALPHA);
    v.log_s = vec3<f32>(log_scales[3u * i], log_scales[3u * i + 1u], log_scales[3u * i + 2u]);
    v.tx = clamp(v.p.x / v.p.z, view.tan_limits.x, view.tan_limits.y);
    v.ty = clamp(v.p.y / v.p.z, view.tan_limits.z, view.tan_limits.w);
    v.mean2d = vec2<f32>(
        view.focal.x * v.p.x / v.p.z + view.focal.z,
        view.focal.y * v.p.y / v.p.z + view.focal.w,
    );
    return v;
}

// Upper bound on the 2D extent along one image axis: the 2D variance (f^2/z^2)(1 + (x/z)^2) of
// the clamped Jacobian row times the largest 3D variance, plus the blur; the relative and absolute
// margins absorb f32 rounding of the exact value computed later.
fn extent_bound(focal: f32, t: f32, iz: f32, var_max: f32, reach: f32) -> f32 {
    let jj = focal * focal * iz * iz * (1.0 + t * t);
    return sqrt(reach * (jj * var_max + COV2D_BLUR)) * 1.001 + 0.01;
}

// The culls that need no covariance: a mirrored view's front side (glass Gaussians never
// reflect), the near plane, an opacity that can never reach alpha 1/255, and the view's tile
// limit tested with a bound on the 2D extent from the largest scale. Every Gaussian these reject
// the exact tests would reject too.
fn passes_cheap_culls(v: ViewPoint) -> bool {
    if view.front_only != 0u {
        if v.glass || !(dot(v.mu - view.plane_centre.xyz, view.plane_normal.xyz) > 0.0) {
            return false;
        }
    }
    if !(v.p.z >= view.near) || !(v.reach > 0.0) {
        return false;
    }
    let iz = 1.0 / v.p.z;
    let var_max = exp(2.0 * max(v.log_s.x, max(v.log_s.y, v.log_s.z)));
    let bound = vec2<f32>(
        extent_bound(view.focal.x, v.tx, iz, var_max, v.reach),
        extent_bound(view.focal.y, v.ty, iz, var_max, v.reach),
    );
    // Only a finite or infinite bound may cull (tile_rect_of treats NaN as empty).
    if bound.x > 0.0 && bound.y > 0.0 {
        let rough = tile_rect_of(v.mean2d, bound, view.width, view.height, view.limit);
        if rough.x >= rough.z {
            return false;
        }
    }
    return true;
}
