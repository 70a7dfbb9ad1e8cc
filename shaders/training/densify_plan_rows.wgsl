// Stage `densify_plan`, second pass (twin: trgs_train::densify::classic::plan_densify): decide
// each Gaussian's fate and how many rows it makes in the new set, in this order: the survivor
// (itself, keeping its Adam moments), its clone, or the two children that replace a split
// parent. An exclusive scan of `rows` then gives each Gaussian its first output row. The report
// (cloned, split, pruned, and the Gaussians drawn since the last densification) is summed per
// workgroup, then once per workgroup into `counts`.
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: DensifyPlanParams;
@group(0) @binding(1) var<storage, read> stats: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> opacity_logits: array<f32>;
@group(0) @binding(3) var<storage, read> log_scales: array<f32>;
// The candidates' exclusive scan: a candidate's rank among them.
@group(0) @binding(4) var<storage, read> ranks: array<u32>;
@group(0) @binding(5) var<storage, read_write> rows: array<u32>;
@group(0) @binding(6) var<storage, read_write> decisions: array<u32>;
// cloned, split, pruned, (the rows, written by the scan), seen (cleared before the pass).
@group(0) @binding(7) var<storage, read_write> counts: array<atomic<u32>>;

#include "shared/densify_rules.wgsl"

var<workgroup> group_counts: array<atomic<u32>, 4>;

fn max_log_scale(i: u32) -> f32 {
    return max(max(log_scales[3u * i], log_scales[3u * i + 1u]), log_scales[3u * i + 2u]);
}

@compute @workgroup_size(256)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    if lid < 4u {
        atomicStore(&group_counts[lid], 0u);
    }
    workgroupBarrier();
    let i = linear_index(gid, nwg, 256u);
    if i < params.count {
        let size = max_log_scale(i);
        let large = params.prune_large != 0u;
        let prune = is_transparent(i) || (large
            && (stats[i].z > params.max_screen_radius || size > params.prune_log_scale));
        let densify = is_candidate(i) && ranks[i] < params.room;
        let split = densify && size > params.clone_log_scale;
        // A clone of a Gaussian pruned for its size would only bring it back; children still
        // over the world-size limit are pruned at once (3DGS prunes after densifying).
        let clone = densify && !split && !prune;
        let children = split && !(large && size > params.child_prune_log_scale);
        let survivor = !split && !prune;
        rows[i] = select(0u, 1u, survivor) + select(0u, 1u, clone) + select(0u, 2u, children);
        decisions[i] = select(0u, DENSIFY_SURVIVOR, survivor) | select(0u, DENSIFY_CLONE, clone)
            | select(0u, DENSIFY_CHILDREN, children);
        if clone {
            atomicAdd(&group_counts[0], 1u);
        }
        if split {
            atomicAdd(&group_counts[1], 1u);
        }
        let pruned = select(0u, 1u, !split && prune) + select(0u, 2u, split && !children);
        if pruned != 0u {
            atomicAdd(&group_counts[2], pruned);
        }
        // Drawn in a view since the last densification (its mean had a gradient): what the
        // frames' keys mostly come from.
        if stats[i].x > 0.0 {
            atomicAdd(&group_counts[3], 1u);
        }
    }
    workgroupBarrier();
    if lid < 4u {
        let c = atomicLoad(&group_counts[lid]);
        if c != 0u {
            // counts[3] is the scan's row total.
            atomicAdd(&counts[select(lid, 4u, lid == 3u)], c);
        }
    }
}
