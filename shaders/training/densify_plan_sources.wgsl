// Stage `densify_plan`, third pass (twin: trgs_train::densify::classic::plan_densify): write each
// Gaussian's rows of the new set as `gather_rows` sources, from its first row (the scan of its
// row counts): the survivor keeps its Adam moments; the clone and the children restart theirs
// (GATHER_ZERO).
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: DensifyPlanParams;
@group(0) @binding(1) var<storage, read> decisions: array<u32>;
@group(0) @binding(2) var<storage, read> first_rows: array<u32>;
@group(0) @binding(3) var<storage, read_write> sources: array<u32>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = linear_index(gid, nwg, 256u);
    if i >= params.count {
        return;
    }
    let d = decisions[i];
    var row = first_rows[i];
    if (d & DENSIFY_SURVIVOR) != 0u {
        sources[row] = i;
        row += 1u;
    }
    if (d & DENSIFY_CLONE) != 0u {
        sources[row] = i | GATHER_ZERO;
        row += 1u;
    }
    if (d & DENSIFY_CHILDREN) != 0u {
        sources[row] = i | GATHER_ZERO;
        sources[row + 1u] = i | GATHER_ZERO;
    }
}
