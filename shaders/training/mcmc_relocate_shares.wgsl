// Stage `mcmc_relocate`, the shares of either round (twin:
// trgs_train::densify::mcmc::relocate::apply_shares), one thread per Gaussian: a row drawn
// N - 1 times takes Eq. 9's opacity and scale for N (from the table by its opacity bin, clamped)
// and restarts its Adam moments; its copies take the same values.
#include "shared/common.wgsl"
#include "shared/relocation.wgsl"

@group(0) @binding(0) var<storage, read> params: McmcRelocateParams;
@group(0) @binding(1) var<storage, read> tally: array<u32>;
@group(0) @binding(2) var<storage, read> share_table: array<vec2<f32>>;
@group(0) @binding(3) var<storage, read_write> new_opacity_logits: array<f32>;
@group(0) @binding(4) var<storage, read_write> new_log_scales: array<f32>;
@group(0) @binding(5) var<storage, read_write> sources: array<u32>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = linear_index(gid, nwg, 256u);
    if i >= params.count || tally[i] == 0u {
        return;
    }
    let share = min(tally[i] + 1u, MAX_SHARE);
    let entry = share_table[opacity_bin(new_opacity_logits[i]) * (MAX_SHARE - 1u) + share - 2u];
    new_opacity_logits[i] = clamp(entry.x, params.min_logit, params.max_logit);
    for (var c = 0u; c < 3u; c++) {
        new_log_scales[3u * i + c] = new_log_scales[3u * i + c] + entry.y;
    }
    sources[i] = sources[i] | GATHER_ZERO;
}
