// The adjoint passes' back-to-front replay of a tile's list (`rasterize_bwd`,
// `rasterize_reflection_bwd`). The including shader defines
//   fn list_entry(i: u32) -> ChunkEntry      the entry of key index i (the sorted key list);
//   fn replay_entry(g: ChunkEntry, li: u32)  list entry li replayed at the thread's pixels, its
//                                            gradients added (subgroup reductions: called in
//                                            uniform control flow);
// and, without BLOCK_WALK, fn store_entry(slot: u32, g: ChunkEntry) and
// fn batch_entry(e: u32) -> ChunkEntry (batch slot e, into and from workgroup memory).
#include "shared/block_walk.wgsl"

#ifdef BLOCK_WALK
// The tile's list entries [0, count) from key index `start`, back to front, by chunks of up to 8
// of the subgroup's lanes (`lane_entry`, `read_list_chunk`): the chunk's entries that reach the
// subgroup's block `b` (all of them when it spans several blocks) are replayed last first.
fn replay_list(start: u32, count: u32, b: BlockOf, lane: u32, size: u32) {
    if count == 0u {
        return;
    }
    let chunk = min(size, 8u);
    var first = ((count - 1u) / chunk) * chunk;
    loop {
        let read = read_list_chunk(ChunkAt(start, first, count, chunk, lane), b);
        let entry = read.entry;
        let reach = read.reach;
        // Written out: each call's lane is then a constant (a loop left dynamic was slower).
        if (reach & 128u) != 0u {
            replay_entry(lane_entry(entry, 7u), first + 7u);
        }
        if (reach & 64u) != 0u {
            replay_entry(lane_entry(entry, 6u), first + 6u);
        }
        if (reach & 32u) != 0u {
            replay_entry(lane_entry(entry, 5u), first + 5u);
        }
        if (reach & 16u) != 0u {
            replay_entry(lane_entry(entry, 4u), first + 4u);
        }
        if (reach & 8u) != 0u {
            replay_entry(lane_entry(entry, 3u), first + 3u);
        }
        if (reach & 4u) != 0u {
            replay_entry(lane_entry(entry, 2u), first + 2u);
        }
        if (reach & 2u) != 0u {
            replay_entry(lane_entry(entry, 1u), first + 1u);
        }
        if (reach & 1u) != 0u {
            replay_entry(lane_entry(entry, 0u), first + 0u);
        }
        if first == 0u {
            break;
        }
        first -= chunk;
    }
}
#else
// The tile's last entry any of its pixels blended.
var<workgroup> max_last: atomic<u32>;

// The tile's list entries [0, sg_last) from key index `start` (those before `end`), back to
// front: the workgroup loads them into workgroup memory a batch of TILE_PIXELS at a time, ROWS
// entries a thread (thread `lid` of the tile), from the last batch any of its pixels blended,
// and each thread replays them one after another up to its subgroup's last, `sg_last`. In
// uniform control flow: it has barriers.
fn replay_batches(start: u32, end: u32, my_last: u32, sg_last: u32, lid: u32) {
    if lid == 0u {
        atomicStore(&max_last, 0u);
    }
    workgroupBarrier();
    atomicMax(&max_last, my_last);
    let last = workgroupUniformLoad(&max_last);
    let rounds = (last + TILE_PIXELS - 1u) / TILE_PIXELS;
    for (var rr = 0u; rr < rounds; rr++) {
        let r = rounds - 1u - rr;
        workgroupBarrier();
        for (var q = 0u; q < ROWS; q++) {
            let slot = lid + q * THREADS;
            let idx = start + r * TILE_PIXELS + slot;
            if idx < end {
                store_entry(slot, list_entry(idx));
            }
        }
        workgroupBarrier();
        let batch = min(TILE_PIXELS, last - r * TILE_PIXELS);
        // Entries [0, mine) of this batch come before the subgroup's last.
        let mine = min(batch, sg_last - min(sg_last, r * TILE_PIXELS));
        for (var j = mine; j > 0u; j--) {
            replay_entry(batch_entry(j - 1u), r * TILE_PIXELS + j - 1u);
        }
    }
}
#endif
