// The adjoint passes' back-to-front replay of a tile's list (`rasterize_bwd`,
// `rasterize_reflection_bwd`). The including shader defines
//   fn list_entry(i: u32) -> ChunkEntry      the entry of key index i (the sorted key list);
//   fn replay_entry(g: ChunkEntry, li: u32)  list entry li replayed at the thread's pixels, its
//                                            gradients added (subgroup reductions: called in
//                                            uniform control flow);
// and, without BLOCK_WALK, batch_entry(e) (batch slot e, from workgroup memory).
#include "shared/block_walk.wgsl"

#ifdef BLOCK_WALK
// The tile's list entries [0, count) from key index `start`, back to front, by chunks of up to 8
// of the subgroup's lanes (`lane_entry`): lane l reads chunk entry l from the key list itself
// and tests it against the subgroup's block (`block_reach`, the tile's blocks of 8 columns by
// ROWS rows; `corner` is the tile's first pixel centre), and the chunk's entries that reach the
// block (all of them when the subgroup spans several blocks) are replayed last first. Each
// subgroup reads the entries it replays itself, without batches in workgroup memory or
// barriers: on lavapipe (the devices with BLOCK_WALK) every workgroup-memory read and write is
// a loop over the lanes, and a tile's one subgroup (eight rows per thread) would only write
// what it reads back.
fn replay_list(
    start: u32,
    count: u32,
    corner: vec2<f32>,
    block: u32,
    one_block: bool,
    lane: u32,
    size: u32,
) {
    if count == 0u {
        return;
    }
    let chunk = min(size, 8u);
    var first = ((count - 1u) / chunk) * chunk;
    loop {
        let e = first + lane;
        var entry = ChunkEntry();
        var reaches = false;
        if lane < chunk && e < count {
            entry = list_entry(start + e);
            reaches = !one_block
                || ((block_reach(entry.conic, entry.mean.xy, corner, vec2<u32>(8u, ROWS)) >> block)
                    & 1u) != 0u;
        }
        let reach = subgroupBallot(reaches).x;
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
// Batch entries [0, mine) of round r, back to front, one after another.
fn replay_batch(mine: u32, r: u32) {
    for (var j = mine; j > 0u; j--) {
        replay_entry(batch_entry(j - 1u), r * TILE_PIXELS + j - 1u);
    }
}
#endif
