// Stage `prefix_sum` (twin: trgs_core::reference::prefix_sum), level scan: an in-place exclusive
// scan of each block of SCAN_BLOCK values (SCAN_ITEMS per thread, then a workgroup scan of the
// thread totals), writing each block's total to `block_sums`. Blocks are joined by scanning
// `block_sums` the same way and adding it back (prefix_sum_add.wgsl). With COUNT_BITS a value
// counts as its number of set bits (a bit mask's words scan into each word's first set bit's
// rank; the levels above scan plain sums).
#include "shared/common.wgsl"
#include "shared/block_width.wgsl"

@group(0) @binding(0) var<storage, read> params: ScanParams;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read_write> block_sums: array<u32>;

var<workgroup> sums: array<u32, SCAN_THREADS>;

@compute @workgroup_size(SCAN_THREADS)
fn main(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    // Blocks past a GPU count are empty: `params.spread` deals the full ones out evenly.
    let block = spread_block(wid, nwg, params.spread);
    // A block past the count (read on the GPU, the dispatch covers the capacity) has nothing to
    // scan and a zero total; returning before the barriers keeps it cheap. (Block 0 scans even
    // an empty input: its total 0 is the scan's total.)
    if block > 0u && block * SCAN_BLOCK >= params.count {
        if lid == 0u && block < params.blocks {
            block_sums[block] = 0u;
        }
        return;
    }
    let base = block * SCAN_BLOCK + lid * SCAN_ITEMS;
    var local: array<u32, SCAN_ITEMS>;
    var total = 0u;
    for (var k = 0u; k < SCAN_ITEMS; k++) {
        local[k] = total;
        if base + k < params.count {
#ifdef COUNT_BITS
            total += countOneBits(data[base + k]);
#else
            total += data[base + k];
#endif
        }
    }
    sums[lid] = total;
    workgroupBarrier();
    // Hillis-Steele inclusive scan of the thread totals.
    for (var offset = 1u; offset < SCAN_THREADS; offset <<= 1u) {
        var v = sums[lid];
        if lid >= offset {
            v += sums[lid - offset];
        }
        workgroupBarrier();
        sums[lid] = v;
        workgroupBarrier();
    }
    var before = 0u;
    if lid > 0u {
        before = sums[lid - 1u];
    }
    for (var k = 0u; k < SCAN_ITEMS; k++) {
        if base + k < params.count {
            data[base + k] = before + local[k];
        }
    }
    // Past 65535 blocks the grid is 2D and its last row of blocks has padding blocks without
    // values (with a spread, whichever row of workgroups takes that row); their index is past
    // the end of `block_sums`, where a clamped write could land on a real total.
    if lid == SCAN_THREADS - 1u && block < params.blocks {
        block_sums[block] = sums[SCAN_THREADS - 1u];
    }
}
