// Stage `densify_plan`, last pass (twin: trgs_train::densify::classic::plan_densify), after
// `gather_rows` has copied the parents into the children's rows: each child of a split parent
// takes a mean drawn from the parent's Gaussian (mean + R (s * z), z standard normal from the
// counter-based generator, numbered 2 i + k) and the parent's log scales less ln(1.6) (3DGS's
// 0.8 N with N = 2). The parents are read from the old set, the children written in the new.
#include "shared/common.wgsl"
#include "shared/random.wgsl"

@group(0) @binding(0) var<storage, read> params: DensifyPlanParams;
@group(0) @binding(1) var<storage, read> decisions: array<u32>;
@group(0) @binding(2) var<storage, read> first_rows: array<u32>;
@group(0) @binding(3) var<storage, read> means: array<f32>;
@group(0) @binding(4) var<storage, read> rotations: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> log_scales: array<f32>;
@group(0) @binding(6) var<storage, read_write> new_means: array<f32>;
@group(0) @binding(7) var<storage, read_write> new_log_scales: array<f32>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = linear_index(gid, nwg, 256u);
    if i >= params.count || (decisions[i] & DENSIFY_CHILDREN) == 0u {
        return;
    }
    // A split parent has no survivor or clone row: its children are its first two rows.
    let first = first_rows[i];
    let r = quat_to_mat(rotations[i]);
    let ls = vec3<f32>(log_scales[3u * i], log_scales[3u * i + 1u], log_scales[3u * i + 2u]);
    let s = exp(ls);
    let mean = vec3<f32>(means[3u * i], means[3u * i + 1u], means[3u * i + 2u]);
    for (var k = 0u; k < 2u; k++) {
        let item = 2u * i + k;
        let z = vec3<f32>(
            noise_normal(params.seed, item, 0u),
            noise_normal(params.seed, item, 1u),
            noise_normal(params.seed, item, 2u),
        );
        let p = mean + r * (s * z);
        let row = first + k;
        for (var c = 0u; c < 3u; c++) {
            new_means[3u * row + c] = p[c];
            new_log_scales[3u * row + c] = ls[c] - params.child_log_shrink;
        }
    }
}
