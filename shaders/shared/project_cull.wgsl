// The cheap culls of stage `project` (twin: trgs_core::reference::project), shared by its two
// kernels: `project_candidates` runs them on every Gaussian for every view of its group and
// lists the survivors per view, `project` recomputes the same quantities for one view's listed
// ones only. Both shaders bind `means`, `log_scales`, `opacity_logits` and `populations` under
// these names; the view's parameters come as an argument.
//
// Why two kernels: CPU adapters (lavapipe) run a branch with every lane of a SIMD chunk masked
// off as if it were taken, so a culled Gaussian costs the full projection and SH evaluation
// unless it never reaches that code; a mirrored view culls most of the scene.

// What the culls need of one Gaussian in any view: read and computed once per Gaussian however
// many views test it.
struct GaussianPoint {
    mu: vec3<f32>,
    opacity: f32,
    // alpha = o G >= 1/255  <=>  the quadratic form is at most `reach` = 2 ln(255 o).
    reach: f32,
    log_s: vec3<f32>,
    // The largest 3D variance, exp(2 max log_s).
    var_max: f32,
    glass: bool,
}

// A Gaussian seen from one view.
struct ViewPoint {
    g: GaussianPoint,
    // Camera-space position.
    p: vec3<f32>,
    // Tangents of the mean clamped to the guard band, and the screen-space mean.
    tx: f32,
    ty: f32,
    mean2d: vec2<f32>,
}

fn gaussian_point(i: u32) -> GaussianPoint {
    var g: GaussianPoint;
    g.mu = vec3<f32>(means[3u * i], means[3u * i + 1u], means[3u * i + 2u]);
    g.glass = populations[i] == POPULATION_GLASS;
    g.opacity = sigmoid(opacity_logits[i]);
    g.reach = 2.0 * log(g.opacity / MIN_ALPHA);
    g.log_s = vec3<f32>(log_scales[3u * i], log_scales[3u * i + 1u], log_scales[3u * i + 2u]);
    g.var_max = exp(2.0 * max(g.log_s.x, max(g.log_s.y, g.log_s.z)));
    return g;
}

// `g` seen from `cam`.
fn in_view(cam: ProjectParams, g: GaussianPoint) -> ViewPoint {
    var v: ViewPoint;
    v.g = g;
    let w = transpose(mat3x3<f32>(cam.row0.xyz, cam.row1.xyz, cam.row2.xyz));
    v.p = w * g.mu + cam.translation.xyz;
    v.tx = clamp(v.p.x / v.p.z, cam.tan_limits.x, cam.tan_limits.y);
    v.ty = clamp(v.p.y / v.p.z, cam.tan_limits.z, cam.tan_limits.w);
    v.mean2d = vec2<f32>(
        cam.focal.x * v.p.x / v.p.z + cam.focal.z,
        cam.focal.y * v.p.y / v.p.z + cam.focal.w,
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
fn passes_cheap_culls(cam: ProjectParams, v: ViewPoint) -> bool {
    if cam.front_only != 0u {
        if v.g.glass || !(dot(v.g.mu - cam.plane_centre.xyz, cam.plane_normal.xyz) > 0.0) {
            return false;
        }
    }
    if !(v.p.z >= cam.near) || !(v.g.reach > 0.0) {
        return false;
    }
    let iz = 1.0 / v.p.z;
    let bound = vec2<f32>(
        extent_bound(cam.focal.x, v.tx, iz, v.g.var_max, v.g.reach),
        extent_bound(cam.focal.y, v.ty, iz, v.g.var_max, v.g.reach),
    );
    // Only a finite or infinite bound may cull (tile_rect_of treats NaN as empty).
    if bound.x > 0.0 && bound.y > 0.0 {
        let rough = tile_rect_of(v.mean2d, bound, cam.width, cam.height, cam.limit);
        if rough.x >= rough.z {
            return false;
        }
    }
    return true;
}
