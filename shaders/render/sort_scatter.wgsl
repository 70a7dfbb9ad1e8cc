// Stage `sort`, stable scatter of one LSD radix pass. Each thread owns SORT_ITEMS consecutive
// keys; their per-digit counts (16-bit fields, two digits per u32) are scanned across the
// workgroup, which gives each thread its first slot per digit inside the block; the block's first
// slot per digit comes from the scanned histogram. Keys keep their order within a digit: the sort
// is stable, as the twin's.
#include "shared/common.wgsl"
#include "shared/block_width.wgsl"
#include "shared/sort_digit.wgsl"
#include "shared/key_pages.wgsl"

@group(0) @binding(0) var<storage, read> params: SortParams;
@group(0) @binding(1) var<storage, read> keys: array<u32>;
@group(0) @binding(2) var<storage, read> values: array<u32>;
@group(0) @binding(3) var<storage, read> hist: array<u32>;
@group(0) @binding(4) var<storage, read_write> out_keys: array<u32>;
@group(0) @binding(5) var<storage, read_write> out_values: array<u32>;
#ifdef PAGED
// The pairs from index params.page on, in and out (a list of two pages: shared/key_pages.wgsl).
@group(0) @binding(6) var<storage, read> keys_hi: array<u32>;
@group(0) @binding(7) var<storage, read> values_hi: array<u32>;
@group(0) @binding(8) var<storage, read_write> out_keys_hi: array<u32>;
@group(0) @binding(9) var<storage, read_write> out_values_hi: array<u32>;

fn value_at(i: u32) -> u32 {
    if i < params.page {
        return values[i];
    }
    return values_hi[i - params.page];
}

fn write_pair(i: u32, key: u32, value: u32) {
    if i < params.page {
        out_keys[i] = key;
        out_values[i] = value;
    } else {
        out_keys_hi[i - params.page] = key;
        out_values_hi[i - params.page] = value;
    }
}
#else
fn value_at(i: u32) -> u32 {
    return values[i];
}

fn write_pair(i: u32, key: u32, value: u32) {
    out_keys[i] = key;
    out_values[i] = value;
}
#endif

// Packed per-digit counts of each thread: 16-bit fields, two digits per u32, SORT_PACKED_VECS
// vec4s per thread.
var<workgroup> scan: array<array<vec4<u32>, SORT_PACKED_VECS>, SORT_THREADS>;
var<workgroup> block_base: array<u32, SORT_RADIX>;

@compute @workgroup_size(SORT_THREADS)
fn main(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    // Blocks past a GPU count are empty: `params.spread` deals the full ones out evenly.
    let block = spread_block(wid, nwg, params.spread);
    // Nothing to move past the last key; returning before the scan's barriers keeps it cheap.
    if block * SORT_BLOCK >= params.count {
        return;
    }
    for (var d = lid; d < SORT_RADIX; d += SORT_THREADS) {
        block_base[d] = hist[d * params.num_blocks + block];
    }
    let base = block * SORT_BLOCK + lid * SORT_ITEMS;
    var packed: array<u32, SORT_PACKED>;
    for (var k = 0u; k < SORT_ITEMS; k++) {
        let slot = base + k;
        if slot < params.count {
            let d = digit_in(key_at(slot));
            packed[d >> 1u] += 1u << ((d & 1u) * 16u);
        }
    }
    for (var v = 0u; v < SORT_PACKED_VECS; v++) {
        let w = 4u * v;
        scan[lid][v] = vec4<u32>(packed[w], packed[w + 1u], packed[w + 2u], packed[w + 3u]);
    }
    workgroupBarrier();
    // Hillis-Steele inclusive scan over threads (16-bit fields cannot overflow: a block holds
    // at most SORT_BLOCK < 65536 keys).
    for (var offset = 1u; offset < SORT_THREADS; offset <<= 1u) {
        var mine = scan[lid];
        if lid >= offset {
            for (var v = 0u; v < SORT_PACKED_VECS; v++) {
                mine[v] += scan[lid - offset][v];
            }
        }
        workgroupBarrier();
        scan[lid] = mine;
        workgroupBarrier();
    }
    // Exclusive prefix of this thread = inclusive - own counts.
    var next: array<u32, SORT_PACKED>;
    for (var v = 0u; v < SORT_PACKED_VECS; v++) {
        let incl = scan[lid][v];
        let w = 4u * v;
        next[w] = incl.x - packed[w];
        next[w + 1u] = incl.y - packed[w + 1u];
        next[w + 2u] = incl.z - packed[w + 2u];
        next[w + 3u] = incl.w - packed[w + 3u];
    }
    for (var k = 0u; k < SORT_ITEMS; k++) {
        let slot = base + k;
        if slot < params.count {
            let key = key_at(slot);
            let value = value_at(slot);
            let d = digit_in(key);
            let shift = (d & 1u) * 16u;
            let rank = (next[d >> 1u] >> shift) & 0xffffu;
            next[d >> 1u] += 1u << shift;
            let dest = block_base[d] + rank;
            write_pair(dest, key, value);
        }
    }
}
