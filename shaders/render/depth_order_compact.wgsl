// Stage `depth_order` (twin: trgs_core::reference::depth_order), first kernel: the present
// entries, in entry order, into the list its sort orders by depth. One thread per word of the
// presence bit mask `tile_counts` set (32 entries); `slots` is the scan of the words' set bits,
// each word's first list slot. Entry order (view, then Gaussian index) makes the list the same
// in every run, and the stable sort keeps it among equal depths: ties go to the lower index, as
// in the twin.
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: ScanParams;
@group(0) @binding(1) var<storage, read> present: array<u32>;
@group(0) @binding(2) var<storage, read> slots: array<u32>;
@group(0) @binding(3) var<storage, read> depths: array<u32>;
@group(0) @binding(4) var<storage, read_write> keys: array<u32>;
@group(0) @binding(5) var<storage, read_write> values: array<u32>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let w = linear_index(gid, nwg, 256u);
    if w >= params.count {
        return;
    }
    var bits = present[w];
    var slot = slots[w];
    // Lowest bit first: entries in increasing order.
    while bits != 0u {
        let e = 32u * w + firstTrailingBit(bits);
        keys[slot] = depths[e];
        values[slot] = e;
        slot += 1u;
        bits &= bits - 1u;
    }
}
