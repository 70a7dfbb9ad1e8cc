// Stage `sort`, stable scatter of one LSD radix pass. Each thread owns SORT_ITEMS consecutive
// keys; their per-digit counts (16-bit fields, two digits per u32) are scanned across the
// workgroup, which gives each thread its first slot per digit inside the block; the block's first
// slot per digit comes from the scanned histogram. Keys keep their order within a digit: the sort
// is stable, as the twin's.
#include "shared/common.wgsl"
#include "shared/sort_digit.wgsl"

@group(0) @binding(0) var<storage, read> params: SortParams;
@group(0) @binding(1) var<storage, read> keys: array<u32>;
@group(0) @binding(2) var<storage, read> values: array<u32>;
// `keys` or `values` again, whichever holds this pass's digit (see shared/sort_digit.wgsl).
@group(0) @binding(3) var<storage, read> digit_words: array<u32>;
@group(0) @binding(4) var<storage, read> hist: array<u32>;
@group(0) @binding(5) var<storage, read_write> out_keys: array<u32>;
@group(0) @binding(6) var<storage, read_write> out_values: array<u32>;

// Packed per-digit counts of each thread: digits 0-7 in `lo` (two per component), 8-15 in `hi`.
var<workgroup> scan_lo: array<vec4<u32>, SORT_THREADS>;
var<workgroup> scan_hi: array<vec4<u32>, SORT_THREADS>;
var<workgroup> block_base: array<u32, 16>;

@compute @workgroup_size(SORT_THREADS)
fn main(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let block = wid.x + wid.y * nwg.x;
    // Nothing to move past the last key; returning before the scan's barriers keeps it cheap.
    if block * SORT_BLOCK >= params.count {
        return;
    }
    if lid < 16u && block < params.num_blocks {
        block_base[lid] = hist[lid * params.num_blocks + block];
    }
    let base = block * SORT_BLOCK + lid * SORT_ITEMS;
    var packed: array<u32, 8>;
    for (var k = 0u; k < SORT_ITEMS; k++) {
        let slot = base + k;
        if slot < params.count {
            let d = digit_in(digit_words[slot]);
            packed[d >> 1u] += 1u << ((d & 1u) * 16u);
        }
    }
    scan_lo[lid] = vec4<u32>(packed[0], packed[1], packed[2], packed[3]);
    scan_hi[lid] = vec4<u32>(packed[4], packed[5], packed[6], packed[7]);
    workgroupBarrier();
    // Hillis-Steele inclusive scan over threads (16-bit fields cannot overflow: a block holds
    // at most SORT_BLOCK < 65536 keys).
    for (var offset = 1u; offset < SORT_THREADS; offset <<= 1u) {
        var lo = scan_lo[lid];
        var hi = scan_hi[lid];
        if lid >= offset {
            lo += scan_lo[lid - offset];
            hi += scan_hi[lid - offset];
        }
        workgroupBarrier();
        scan_lo[lid] = lo;
        scan_hi[lid] = hi;
        workgroupBarrier();
    }
    // Exclusive prefix of this thread = inclusive - own counts.
    let incl_lo = scan_lo[lid];
    let incl_hi = scan_hi[lid];
    var next: array<u32, 8>;
    next[0] = incl_lo.x - packed[0];
    next[1] = incl_lo.y - packed[1];
    next[2] = incl_lo.z - packed[2];
    next[3] = incl_lo.w - packed[3];
    next[4] = incl_hi.x - packed[4];
    next[5] = incl_hi.y - packed[5];
    next[6] = incl_hi.z - packed[6];
    next[7] = incl_hi.w - packed[7];
    for (var k = 0u; k < SORT_ITEMS; k++) {
        let slot = base + k;
        if slot < params.count {
            // Both words are moved anyway: the digit comes from the one loaded.
            let key = keys[slot];
            let value = values[slot];
            let d = digit_in(select(value, key, params.from_keys != 0u));
            let shift = (d & 1u) * 16u;
            let rank = (next[d >> 1u] >> shift) & 0xffffu;
            next[d >> 1u] += 1u << shift;
            let dest = block_base[d] + rank;
            out_keys[dest] = key;
            out_values[dest] = value;
        }
    }
}
