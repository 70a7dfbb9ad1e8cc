// Stage `densify_stats` (twin: trgs_train::densify::DensifyStats::add): one pass's share of a
// training step's densification statistics, one thread per Gaussian, summed where the gradients
// are made so that no step reads them back. The camera's pass runs first (`first_pass`), then
// each mirrored pass: a Gaussian seen in any of them counts one observation, and its gradient is
// the sum of the passes' norms. stats[i] = (sum of norms, observations, largest screen radius,
// seen in this step).
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: DensifyStatsParams;
@group(0) @binding(1) var<storage, read> projected: array<ProjectedGaussian>;
// PROJECTED_GRAD_FLOATS per Gaussian; the first two are dL/d(mean2d).
@group(0) @binding(2) var<storage, read> grads: array<f32>;
@group(0) @binding(3) var<storage, read_write> stats: array<vec4<f32>>;
// The step's `step_guard`: nothing is added while it is set.
@group(0) @binding(4) var<storage, read> guard: array<u32>;

// |v| without overflow for components near the f32 limit.
fn norm2(v: vec2<f32>) -> f32 {
    let m = max(abs(v.x), abs(v.y));
    if m == 0.0 || m > 3.0e38 {
        return m;
    }
    return m * length(v / m);
}

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = linear_index(gid, nwg, 256u);
    if i >= params.count || guard[0] != 0u {
        return;
    }
    var s = stats[i];
    if params.first_pass != 0u {
        s.w = 0.0;
    }
    let p = projected[i];
    if (p.flags & FLAG_VISIBLE) != 0u {
        // 3DGS measures the gradient in NDC: d/d(ndc) = d/d(pixel) * size / 2.
        let base = PROJECTED_GRAD_FLOATS * i;
        let g = vec2<f32>(grads[base] * params.half_width, grads[base + 1u] * params.half_height);
        s.x += norm2(g);
        s.z = max(s.z, max(p.extent.x, p.extent.y));
        if s.w == 0.0 {
            s.y += 1.0;
            s.w = 1.0;
        }
    }
    stats[i] = s;
}
