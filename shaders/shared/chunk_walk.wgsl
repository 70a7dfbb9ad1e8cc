// The forward passes' walk through a tile's list (`rasterize`, `rasterize_reflection`). The
// including shader defines
//   fn step_entry(g: ChunkEntry, li: u32)    list entry li at the thread's pixels;
//   fn walk_over() -> bool                   whether the thread's pixels have all stopped;
// with BLOCK_WALK, fn list_entry(i: u32) -> ChunkEntry (the entry of key index i, the sorted key
// list); without, fn batch_entry(e: u32) -> ChunkEntry (batch slot e, from workgroup memory).
#include "shared/block_walk.wgsl"

#ifdef BLOCK_WALK
// The tile's list entries [0, count) from key index `start`, in order, by chunks of up to 8 of
// the subgroup's lanes (`lane_entry`, `read_list_chunk`), until the subgroup's pixels have all
// stopped: the chunk's entries that reach the subgroup's block `b` (all of them when it spans
// several blocks) are stepped through in order.
fn walk_list(start: u32, count: u32, b: BlockOf, lane: u32, size: u32) {
    let chunk = min(size, 8u);
    for (var first = 0u; first < count; first += chunk) {
        if subgroupAll(walk_over()) {
            break;
        }
        let read = read_list_chunk(ChunkAt(start, first, count, chunk, lane), b);
        let mine = read.entry;
        let reach = read.reach;
        // Written out: each call's lane is then a constant (a loop left dynamic was slower).
        if (reach & 1u) != 0u {
            step_entry(lane_entry(mine, 0u), first + 0u);
        }
        if (reach & 2u) != 0u {
            step_entry(lane_entry(mine, 1u), first + 1u);
        }
        if (reach & 4u) != 0u {
            step_entry(lane_entry(mine, 2u), first + 2u);
        }
        if (reach & 8u) != 0u {
            step_entry(lane_entry(mine, 3u), first + 3u);
        }
        if (reach & 16u) != 0u {
            step_entry(lane_entry(mine, 4u), first + 4u);
        }
        if (reach & 32u) != 0u {
            step_entry(lane_entry(mine, 5u), first + 5u);
        }
        if (reach & 64u) != 0u {
            step_entry(lane_entry(mine, 6u), first + 6u);
        }
        if (reach & 128u) != 0u {
            step_entry(lane_entry(mine, 7u), first + 7u);
        }
    }
}
#else
// Batch entries [0, batch) of round r, one after another.
fn walk_batch(batch: u32, r: u32) {
    for (var j = 0u; j < batch && !walk_over(); j++) {
        step_entry(batch_entry(j), r * TILE_PIXELS + j);
    }
}
#endif
