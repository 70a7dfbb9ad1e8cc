// The adjoint passes' back-to-front replay of one batch of a tile's list (`rasterize_bwd`,
// `rasterize_reflection_bwd`). The including shader defines
//   fn batch_entry(e: u32) -> ChunkEntry     batch entry e, from workgroup memory;
//   fn replay_entry(g: ChunkEntry, li: u32)  list entry li replayed at the thread's pixels, its
//                                            gradients added (subgroup reductions: called in
//                                            uniform control flow);
// and, with BLOCK_WALK, `s_blocks` (shared/block_walk.wgsl).
#include "shared/block_walk.wgsl"

#ifdef BLOCK_WALK
// Batch entries [0, mine) of round r, back to front, by chunks of up to 8 of the subgroup's
// lanes (`lane_entry`): lane l reads chunk entry l, and the chunk's entries that reach the
// subgroup's block (all of them when the subgroup spans several blocks) are replayed last first.
fn replay_batch(mine: u32, r: u32, block: u32, one_block: bool, lane: u32, size: u32) {
    if mine == 0u {
        return;
    }
    let chunk = min(size, 8u);
    var first = ((mine - 1u) / chunk) * chunk;
    loop {
        let read = read_chunk(first, mine, chunk, lane, block, one_block);
        let entry = read.entry;
        let reach = read.reach;
        // Written out: each call's lane is then a constant (a loop left dynamic was slower).
        let li = r * TILE_PIXELS + first;
        if (reach & 128u) != 0u {
            replay_entry(lane_entry(entry, 7u), li + 7u);
        }
        if (reach & 64u) != 0u {
            replay_entry(lane_entry(entry, 6u), li + 6u);
        }
        if (reach & 32u) != 0u {
            replay_entry(lane_entry(entry, 5u), li + 5u);
        }
        if (reach & 16u) != 0u {
            replay_entry(lane_entry(entry, 4u), li + 4u);
        }
        if (reach & 8u) != 0u {
            replay_entry(lane_entry(entry, 3u), li + 3u);
        }
        if (reach & 4u) != 0u {
            replay_entry(lane_entry(entry, 2u), li + 2u);
        }
        if (reach & 2u) != 0u {
            replay_entry(lane_entry(entry, 1u), li + 1u);
        }
        if (reach & 1u) != 0u {
            replay_entry(lane_entry(entry, 0u), li + 0u);
        }
        if first == 0u {
            break;
        }
        first -= chunk;
    }
}
#else
// Batch entries [0, mine) of round r, back to front, one after another.
fn replay_batch(mine: u32, r: u32) {
    for (var j = mine; j > 0u; j--) {
        replay_entry(batch_entry(j - 1u), r * TILE_PIXELS + j - 1u);
    }
}
#endif
