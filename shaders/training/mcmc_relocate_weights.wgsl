// Stage `mcmc_relocate`, first pass (twin: trgs_train::densify::mcmc::plan_relocation), one
// thread per Gaussian: flag the dead primary Gaussians (to be ranked by a scan), weigh the live
// primary ones by their opacity bin (to be scanned for the draws), and start the new set's
// working rows as copies of the old: its opacities, log scales and gather sources.
#include "shared/common.wgsl"
#include "shared/relocation.wgsl"

@group(0) @binding(0) var<storage, read> params: McmcRelocateParams;
@group(0) @binding(1) var<storage, read> opacity_logits: array<f32>;
@group(0) @binding(2) var<storage, read> log_scales: array<f32>;
@group(0) @binding(3) var<storage, read> populations: array<u32>;
@group(0) @binding(4) var<storage, read> weight_table: array<u32>;
@group(0) @binding(5) var<storage, read_write> dead: array<u32>;
@group(0) @binding(6) var<storage, read_write> weights: array<u32>;
@group(0) @binding(7) var<storage, read_write> new_opacity_logits: array<f32>;
@group(0) @binding(8) var<storage, read_write> new_log_scales: array<f32>;
@group(0) @binding(9) var<storage, read_write> sources: array<u32>;
@group(0) @binding(10) var<storage, read_write> tally: array<u32>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = linear_index(gid, nwg, 256u);
    if i >= params.count {
        return;
    }
    let l = opacity_logits[i];
    let primary = populations[i] != POPULATION_GLASS;
    let is_dead = primary && l <= params.dead_logit;
    dead[i] = select(0u, 1u, is_dead);
    weights[i] = select(0u, weight_table[opacity_bin(l)], primary && !is_dead);
    new_opacity_logits[i] = l;
    for (var c = 0u; c < 3u; c++) {
        new_log_scales[3u * i + c] = log_scales[3u * i + c];
    }
    sources[i] = i;
    tally[i] = 0u;
}
