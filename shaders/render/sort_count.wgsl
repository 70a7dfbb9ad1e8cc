// Stage `sort` (twins: trgs_core::reference::sort_keys, depth_order), digit histogram of one LSD radix pass:
// for each block of SORT_BLOCK keys, how many have each digit. The histogram is stored
// digit-major (`hist[digit * num_blocks + block]`) so that its exclusive scan is every block's
// first output slot per digit.
#include "shared/common.wgsl"
#include "shared/block_width.wgsl"
#include "shared/sort_digit.wgsl"
#include "shared/key_pages.wgsl"

@group(0) @binding(0) var<storage, read> params: SortParams;
// Only the keys: counting needs no values.
@group(0) @binding(1) var<storage, read> keys: array<u32>;
@group(0) @binding(2) var<storage, read_write> hist: array<u32>;
#ifdef PAGED
// Keys from index params.page on (shared/key_pages.wgsl).
@group(0) @binding(3) var<storage, read> keys_hi: array<u32>;
#endif

var<workgroup> counts: array<atomic<u32>, SORT_RADIX>;

@compute @workgroup_size(SORT_THREADS)
fn main(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    // Blocks past a GPU count are empty: `params.spread` deals the full ones out evenly.
    let block = spread_block(wid, nwg, params.spread);
    // A block past the last key (the count may come from the GPU, the dispatch covers the
    // capacity) has an empty histogram; returning before the barrier keeps it cheap.
    if block * SORT_BLOCK >= params.count {
        // (A 2D grid's padding blocks are past num_blocks: they have no histogram column.)
        for (var d = lid; d < SORT_RADIX && block < params.num_blocks; d += SORT_THREADS) {
            hist[d * params.num_blocks + block] = 0u;
        }
        return;
    }
    for (var d = lid; d < SORT_RADIX; d += SORT_THREADS) {
        atomicStore(&counts[d], 0u);
    }
    workgroupBarrier();
    let base = block * SORT_BLOCK + lid * SORT_ITEMS;
    for (var k = 0u; k < SORT_ITEMS; k++) {
        let slot = base + k;
        if slot < params.count {
            atomicAdd(&counts[digit_in(key_at(slot))], 1u);
        }
    }
    workgroupBarrier();
    for (var d = lid; d < SORT_RADIX; d += SORT_THREADS) {
        hist[d * params.num_blocks + block] = atomicLoad(&counts[d]);
    }
}
