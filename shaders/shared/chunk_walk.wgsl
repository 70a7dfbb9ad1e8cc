// The forward passes' walk through one batch of a tile's list (`rasterize`,
// `rasterize_reflection`). The including shader defines
//   fn batch_entry(e: u32) -> ChunkEntry     batch entry e, from workgroup memory;
//   fn step_entry(g: ChunkEntry, li: u32)    list entry li at the thread's pixels;
//   fn walk_over() -> bool                   whether the thread's pixels have all stopped;
// and, with BLOCK_WALK, `s_blocks` (an entry's block mask per batch slot, shared/block_walk.wgsl).
#include "shared/block_walk.wgsl"

#ifdef BLOCK_WALK
// Lane `lane`'s entry of the chunk of up to `chunk` batch entries from `first` (those before
// `end`), read from workgroup memory by the includer's `batch_entry`, and the subgroup's ballot
// of the chunk's entries that reach its block (all of them when it spans several blocks).
struct Chunk {
    entry: ChunkEntry,
    reach: u32,
}

fn read_chunk(first: u32, end: u32, chunk: u32, lane: u32, block: u32, one_block: bool) -> Chunk {
    let e = first + lane;
    var entry = ChunkEntry();
    var reaches = false;
    if lane < chunk && e < end {
        entry = batch_entry(e);
        reaches = !one_block || ((s_blocks[e] >> block) & 1u) != 0u;
    }
    return Chunk(entry, subgroupBallot(reaches).x);
}

// Batch entries [0, batch) of round r, by chunks of up to 8 of the subgroup's lanes
// (`lane_entry`): lane l reads chunk entry l, and the chunk's entries that reach the subgroup's
// block (all of them when the subgroup spans several blocks) are stepped through in order.
fn walk_batch(batch: u32, r: u32, block: u32, one_block: bool, lane: u32, size: u32) {
    let chunk = min(size, 8u);
    for (var first = 0u; first < batch; first += chunk) {
        if subgroupAll(walk_over()) {
            break;
        }
        let read = read_chunk(first, batch, chunk, lane, block, one_block);
        let mine = read.entry;
        let reach = read.reach;
        // Written out: each call's lane is then a constant (a loop left dynamic was slower).
        let li = r * TILE_PIXELS + first;
        if (reach & 1u) != 0u {
            step_entry(lane_entry(mine, 0u), li + 0u);
        }
        if (reach & 2u) != 0u {
            step_entry(lane_entry(mine, 1u), li + 1u);
        }
        if (reach & 4u) != 0u {
            step_entry(lane_entry(mine, 2u), li + 2u);
        }
        if (reach & 8u) != 0u {
            step_entry(lane_entry(mine, 3u), li + 3u);
        }
        if (reach & 16u) != 0u {
            step_entry(lane_entry(mine, 4u), li + 4u);
        }
        if (reach & 32u) != 0u {
            step_entry(lane_entry(mine, 5u), li + 5u);
        }
        if (reach & 64u) != 0u {
            step_entry(lane_entry(mine, 6u), li + 6u);
        }
        if (reach & 128u) != 0u {
            step_entry(lane_entry(mine, 7u), li + 7u);
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
