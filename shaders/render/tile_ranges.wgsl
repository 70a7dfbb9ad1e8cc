// Stage `tile_ranges` (twin: trgs_core::reference::tile_ranges): each tile's half-open range in
// the sorted key list. `ranges` is cleared to zero first, so tiles without keys stay empty.
#include "shared/common.wgsl"
#include "shared/key_pages.wgsl"

@group(0) @binding(0) var<storage, read> params: ScanParams;
@group(0) @binding(1) var<storage, read> keys: array<u32>;
@group(0) @binding(2) var<storage, read_write> ranges: array<u32>;
#ifdef PAGED
// Keys from index params.page on (shared/key_pages.wgsl).
@group(0) @binding(3) var<storage, read> keys_hi: array<u32>;
#endif

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let slot = linear_index(gid, nwg, 256u);
    let n = params.count;
    if slot >= n {
        return;
    }
    let tile = key_at(slot);
    if slot == 0u || key_at(slot - 1u) != tile {
        ranges[2u * tile] = slot;
    }
    if slot + 1u == n || key_at(slot + 1u) != tile {
        ranges[2u * tile + 1u] = slot + 1u;
    }
}
