// Stage `mcmc_relocate`, the draws of either round (twin: trgs_train::densify::mcmc::draw), one
// thread per draw: a uniform integer below the weights' total, then a binary search of their
// exclusive scan for the last row at or below it (whose weight is then not zero); each row
// counts the draws that chose it. No draws when every weight is zero.
#include "shared/common.wgsl"
#include "shared/relocation.wgsl"

@group(0) @binding(0) var<storage, read> params: McmcRelocateParams;
// The number of draws in the first word: the dead count (a scan's total) or the growth.
@group(0) @binding(1) var<storage, read> draw_count: array<u32>;
// The weights' total in the first word (their scan's).
@group(0) @binding(2) var<storage, read> total: array<u32>;
@group(0) @binding(3) var<storage, read> cumulative: array<u32>;
@group(0) @binding(4) var<storage, read_write> tally: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> draws: array<u32>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let j = linear_index(gid, nwg, 256u);
    let t = total[0];
    if j >= draw_count[0] || t == 0u {
        return;
    }
    let u = draw_below(params.seed, j, t);
    var lo = 0u;
    var hi = params.count;
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if cumulative[mid] <= u {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    draws[j] = lo;
    atomicAdd(&tally[lo], 1u);
}
