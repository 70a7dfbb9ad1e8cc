// Stage `depth_order` (twin: trgs_core::reference::depth_order), first kernel: the present
// entries, in entry order, into the list its sort orders by depth. `slots` is the exclusive scan
// of the presence flags `tile_counts` set, `total` the scan's total: entry e is present when the
// next slot is past its own. Entry order (view, then Gaussian index) makes the list the same in
// every run, and the stable sort keeps it among equal depths: ties go to the lower index, as in
// the twin.
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: ScanParams;
@group(0) @binding(1) var<storage, read> slots: array<u32>;
@group(0) @binding(2) var<storage, read> total: array<u32>;
@group(0) @binding(3) var<storage, read> depths: array<u32>;
@group(0) @binding(4) var<storage, read_write> keys: array<u32>;
@group(0) @binding(5) var<storage, read_write> values: array<u32>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let e = linear_index(gid, nwg, 256u);
    if e >= params.count {
        return;
    }
    let slot = slots[e];
    var next = total[0];
    if e + 1u < params.count {
        next = slots[e + 1u];
    }
    if next > slot {
        keys[slot] = depths[e];
        values[slot] = e;
    }
}
