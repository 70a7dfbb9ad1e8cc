// The walk by pixel blocks of the rasterize passes on devices whose subgroups hold at most 8 lanes
// (the define BLOCK_WALK; trgs_render::Capabilities::block_walk): a tile's pixels are split into
// blocks of 8 threads' pixels, an entry's mask says which blocks it can reach, and a subgroup
// lying in one block steps only through the entries that reach it (the chunk walks,
// shared/chunk_walk.wgsl and shared/chunk_replay.wgsl). On a CPU adapter a subgroup is a SIMD
// vector, which leaves a loop together but runs a skipped branch's body anyway, so without this
// it pays for every entry of the tile's list whether it reaches its pixels or not.

// One list entry as the walks take it (from a batch in workgroup memory, or with BLOCK_WALK from
// the key list and then from lane to lane: `lane_entry`): the 2D mean and what the pass keeps beside it, the conic with the opacity, the
// colour with the depth or the reflection intensity, and the Gaussian's index.
struct ChunkEntry {
    mean: vec4<f32>,
    conic: vec4<f32>,
    color: vec4<f32>,
    index: u32,
}

// The entry of key index i as pass 1 and its adjoint take it: (mean, m, 1 for glass), the conic
// with the opacity, (colour, depth). The including shader binds the key values and the
// projected records (shared/raster_pages.wgsl).
fn pass1_entry(i: u32) -> ChunkEntry {
    let gi = value_at(i);
    let g = projected_at(gi);
    let glass = f32((g.flags & FLAG_GLASS) != 0u);
    return ChunkEntry(vec4<f32>(g.mean2d, g.mask, glass), g.conic, g.color, gi);
}

// The entry of key index i as pass 2 and its adjoint take it: the mean, the conic with the
// opacity, (colour, reflection intensity a).
fn pass2_entry(i: u32) -> ChunkEntry {
    let gi = value_at(i);
    let g = projected_at(gi);
    let color = vec4<f32>(g.color.xyz, g.reflection);
    return ChunkEntry(vec4<f32>(g.mean2d, 0.0, 0.0), g.conic, color, gi);
}

#ifdef BLOCK_WALK
// Which blocks of a tile one Gaussian can reach (twin: reference::block_reach, where the
// reasoning is set out): the tile is split row by row into blocks of `block` pixels (x, y), and
// bit k (block k) is clear only when o G < MIN_ALPHA at all of the block's pixels, so that
// alpha_at returns -1 there and the walk may skip the entry for the block. `corner` is the tile's
// first pixel centre. The test is the ellipse o G = MIN_ALPHA itself (r = 2 ln(o / MIN_ALPHA)),
// widened by 2% and 0.05 px plus 1e-6 of the coordinates: per row of blocks, its x-range over the
// row's band of pixel centres (the leftmost or rightmost point where it lies in the band, else an
// end of the band). Any conic that is ill-conditioned, not positive definite or not finite
// reaches every block.
fn block_reach(conic: vec4<f32>, mean: vec2<f32>, corner: vec2<f32>, block: vec2<u32>) -> u32 {
    let per_row = TILE_SIZE / block.x;
    let rows = TILE_SIZE / block.y;
    let all = (1u << (per_row * rows)) - 1u;
    let a = conic.x;
    let b = conic.y;
    let c = conic.z;
    let det = a * c - b * b;
    let r = 2.0 * log(conic.w / MIN_ALPHA) * 1.0404;
    let trace = a + c;
    if !(det > 0.0) || !(a > 0.0) || !(r > 0.0) || !(trace * trace <= 1e4 * det)
        || !(abs(mean.x) + abs(mean.y) <= 1e7) {
        return all;
    }
    let slack = 0.05 + 1e-6 * (abs(mean.x) + abs(mean.y) + abs(corner.x) + abs(corner.y));
    // Half-extents, and the y of the leftmost point (the rightmost one's is its negative).
    let half = vec2<f32>(sqrt(r * c / det), sqrt(r * a / det));
    let y_left = b * sqrt(r / (c * det));
    if !(half.x < 1e30) || !(half.y < 1e30) || !(abs(y_left) < 1e30) {
        return all;
    }
    // A block's pixel centres span block - 1 px from its first.
    let span = vec2<f32>(block - vec2<u32>(1u));
    var bits = 0u;
    for (var row = 0u; row < rows; row++) {
        // The row's band of pixel centres, relative to the mean, within the ellipse's extent.
        let top = corner.y + f32(row * block.y) - mean.y;
        let y0 = max(top - slack, -half.y);
        let y1 = min(top + span.y + slack, half.y);
        if !(y0 <= y1) {
            continue;
        }
        var left = -half.x;
        if !(y0 <= y_left && y_left <= y1) {
            left = min(ellipse_edge(a, b, det, r, y0, -1.0), ellipse_edge(a, b, det, r, y1, -1.0));
        }
        var right = half.x;
        if !(y0 <= -y_left && -y_left <= y1) {
            right = max(ellipse_edge(a, b, det, r, y0, 1.0), ellipse_edge(a, b, det, r, y1, 1.0));
        }
        let lo = mean.x + left - slack;
        let hi = mean.x + right + slack;
        for (var column = 0u; column < per_row; column++) {
            let first = corner.x + f32(column * block.x);
            if hi >= first && lo <= first + span.x {
                bits |= 1u << (row * per_row + column);
            }
        }
    }
    return bits;
}

// The x of the ellipse a x^2 + 2 b x y + c y^2 = r (det = a c - b^2) at height y, relative to its
// centre: the left edge for side -1, the right for 1.
fn ellipse_edge(a: f32, b: f32, det: f32, r: f32, y: f32, side: f32) -> f32 {
    return (-b * y + side * sqrt(max(a * r - det * y * y, 0.0))) / a;
}

// Lane k's `e` on every lane of the subgroup (k < 8, the same on every lane). The chunk walks
// (shared/chunk_walk.wgsl, shared/chunk_replay.wgsl) have lane l read chunk entry l from the
// key list and step through the chunk's entries with their values broadcast from their lane.
// Lavapipe (Mesa 22) reads memory one lane at a time, in a loop over the SIMD vector, so a read
// a lane per chunk costs far less than reads a step; a broadcast is a register move. WGSL takes
// a broadcast's lane as a constant, hence the switch.
fn lane_entry(e: ChunkEntry, k: u32) -> ChunkEntry {
    switch k {
        case 0u: {
            return ChunkEntry(subgroupBroadcast(e.mean, 0u), subgroupBroadcast(e.conic, 0u), subgroupBroadcast(e.color, 0u), subgroupBroadcast(e.index, 0u));
        }
        case 1u: {
            return ChunkEntry(subgroupBroadcast(e.mean, 1u), subgroupBroadcast(e.conic, 1u), subgroupBroadcast(e.color, 1u), subgroupBroadcast(e.index, 1u));
        }
        case 2u: {
            return ChunkEntry(subgroupBroadcast(e.mean, 2u), subgroupBroadcast(e.conic, 2u), subgroupBroadcast(e.color, 2u), subgroupBroadcast(e.index, 2u));
        }
        case 3u: {
            return ChunkEntry(subgroupBroadcast(e.mean, 3u), subgroupBroadcast(e.conic, 3u), subgroupBroadcast(e.color, 3u), subgroupBroadcast(e.index, 3u));
        }
        case 4u: {
            return ChunkEntry(subgroupBroadcast(e.mean, 4u), subgroupBroadcast(e.conic, 4u), subgroupBroadcast(e.color, 4u), subgroupBroadcast(e.index, 4u));
        }
        case 5u: {
            return ChunkEntry(subgroupBroadcast(e.mean, 5u), subgroupBroadcast(e.conic, 5u), subgroupBroadcast(e.color, 5u), subgroupBroadcast(e.index, 5u));
        }
        case 6u: {
            return ChunkEntry(subgroupBroadcast(e.mean, 6u), subgroupBroadcast(e.conic, 6u), subgroupBroadcast(e.color, 6u), subgroupBroadcast(e.index, 6u));
        }
        default: {
            return ChunkEntry(subgroupBroadcast(e.mean, 7u), subgroupBroadcast(e.conic, 7u), subgroupBroadcast(e.color, 7u), subgroupBroadcast(e.index, 7u));
        }
    }
}

// Lane `lane`'s entry of the chunk of up to `chunk` list entries from `first` (those before
// `count`), read from the key list from index `start` by the includer's `list_entry`, and the
// subgroup's ballot of the chunk's entries that reach its block (`block_reach` with blocks of
// `size` pixels from the tile's first pixel centre `corner`; all of them when the subgroup spans
// several blocks). Each subgroup reads the entries it walks itself, with no batch in workgroup
// memory and no barrier: on lavapipe, the devices with BLOCK_WALK, every workgroup-memory write
// and read is a loop over the lanes, which a batch pays once to write and once per subgroup to
// read back.
struct Chunk {
    entry: ChunkEntry,
    reach: u32,
}

struct ChunkAt {
    start: u32,
    first: u32,
    count: u32,
    chunk: u32,
    lane: u32,
}

struct BlockOf {
    corner: vec2<f32>,
    size: vec2<u32>,
    block: u32,
    one_block: bool,
}

fn read_list_chunk(at: ChunkAt, b: BlockOf) -> Chunk {
    let e = at.first + at.lane;
    var entry = ChunkEntry();
    var reaches = false;
    if at.lane < at.chunk && e < at.count {
        entry = list_entry(at.start + e);
        reaches = !b.one_block
            || ((block_reach(entry.conic, entry.mean.xy, b.corner, b.size) >> b.block) & 1u) != 0u;
    }
    return Chunk(entry, subgroupBallot(reaches).x);
}

// Whether this invocation's subgroup lies in one block (the walk may skip only then).
fn in_one_block(block: u32) -> bool {
    return subgroupAll(subgroupBroadcastFirst(block) == block);
}

#endif
