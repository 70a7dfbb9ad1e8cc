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
fn main(
    @builtin(local_invocation_id) lid: vec3<u32>,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    // Strided over the keys' blocks: with the count known on the GPU only, no workgroup passes
    // over the empty blocks of the list's capacity.
    let n = params.count;
    for (var block = strided_first(wid, nwg); block < blocks_of(n, 256u); block += strided_step(nwg)) {
        let slot = block * 256u + lid.x;
        if slot < n {
            range_edges(slot, n);
        }
    }
}

// Where slot `slot` of the `n` sorted keys starts or ends its tile's range.
fn range_edges(slot: u32, n: u32) {
    let tile = key_at(slot);
    if slot == 0u || key_at(slot - 1u) != tile {
        ranges[2u * tile] = slot;
    }
    if slot + 1u == n || key_at(slot + 1u) != tile {
        ranges[2u * tile + 1u] = slot + 1u;
    }
}
