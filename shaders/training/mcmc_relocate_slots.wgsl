// Stage `mcmc_relocate`, between the rounds (twin: plan_relocation), one thread per Gaussian:
// the k-th dead Gaussian (its rank, a scan of the dead flags) becomes a copy of the k-th draw,
// whose share was applied, with restarting moments; then every row's weight for the growth's
// draws comes from its new opacity, and its tally starts over.
#include "shared/common.wgsl"
#include "shared/relocation.wgsl"

@group(0) @binding(0) var<storage, read> params: McmcRelocateParams;
@group(0) @binding(1) var<storage, read> opacity_logits: array<f32>;
@group(0) @binding(2) var<storage, read> populations: array<u32>;
@group(0) @binding(3) var<storage, read> dead_ranks: array<u32>;
// The first round's weight total in the first word: no draws were made when it is zero.
@group(0) @binding(4) var<storage, read> total: array<u32>;
@group(0) @binding(5) var<storage, read> draws: array<u32>;
@group(0) @binding(6) var<storage, read> weight_table: array<u32>;
@group(0) @binding(7) var<storage, read_write> new_opacity_logits: array<f32>;
@group(0) @binding(8) var<storage, read_write> new_log_scales: array<f32>;
@group(0) @binding(9) var<storage, read_write> sources: array<u32>;
@group(0) @binding(10) var<storage, read_write> weights: array<u32>;
@group(0) @binding(11) var<storage, read_write> tally: array<u32>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = linear_index(gid, nwg, 256u);
    if i >= params.count {
        return;
    }
    let primary = populations[i] != POPULATION_GLASS;
    // A dead row reads its source's row, which no thread of this pass writes (sources live).
    if primary && opacity_logits[i] <= params.dead_logit && total[0] != 0u {
        let s = draws[dead_ranks[i]];
        new_opacity_logits[i] = new_opacity_logits[s];
        for (var c = 0u; c < 3u; c++) {
            new_log_scales[3u * i + c] = new_log_scales[3u * s + c];
        }
        sources[i] = sources[s] | GATHER_ZERO;
    }
    weights[i] = select(0u, weight_table[opacity_bin(new_opacity_logits[i])], primary);
    tally[i] = 0u;
}
