// The walk by pixel blocks of the rasterize passes on devices whose subgroups hold at most 8 lanes
// (the define BLOCK_WALK; trgs_render::Capabilities::block_walk): a tile's pixels are split into
// blocks of 8 threads' pixels, an entry's mask says which blocks it can reach, and a subgroup
// lying in one block steps from one reaching entry to the next. On a CPU adapter a subgroup is a
// SIMD vector, which leaves a loop together but runs a skipped branch's body anyway, so without
// this it pays for every entry of the tile's list whether it reaches its pixels or not. Without
// BLOCK_WALK only `entry_before` is left, stepping to the previous entry; with it the including
// shader declares `s_blocks` (an entry's block mask per batch slot). The forward passes step
// ahead (`next_entry`), the backward ones back (`entry_before`).
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

// The first set bit at or after j of the 64-bit mask (lo, hi), or 64.
fn next_in(lo: u32, hi: u32, j: u32) -> u32 {
    let m_lo = select(0u, lo & (0xffffffffu << min(j, 31u)), j < 32u);
    let m_hi = select(0u, hi & (0xffffffffu << (max(j, 32u) - 32u)), j < 64u);
    let in_hi = select(64u, 32u + firstTrailingBit(m_hi), m_hi != 0u);
    return select(in_hi, firstTrailingBit(m_lo), m_lo != 0u);
}

// The last set bit at or before j (j < 64) of the 64-bit mask (lo, hi), or 64 when there is none.
fn prev_in(lo: u32, hi: u32, j: u32) -> u32 {
    let m_hi = select(0u, hi & (0xffffffffu >> (63u - max(j, 32u))), j >= 32u);
    let m_lo = lo & select(0xffffffffu >> (31u - min(j, 31u)), 0xffffffffu, j >= 32u);
    let in_lo = select(64u, firstLeadingBit(m_lo), m_lo != 0u);
    return select(in_lo, 32u + firstLeadingBit(m_hi), m_hi != 0u);
}

// Whether this invocation's subgroup lies in one block (the walk may skip only then).
fn in_one_block(block: u32) -> bool {
    return subgroupAll(subgroupBroadcastFirst(block) == block);
}

// The walk's next entry at or after j in `reach` (from `reaching`), or 64. Broadcast from the
// subgroup's first lane (every lane has the same one) so that the compiler sees a uniform index:
// the loads of the entry stay single loads instead of one per lane.
fn next_entry(reach: vec2<u32>, j: u32) -> u32 {
    return subgroupBroadcastFirst(next_in(reach.x, reach.y, j));
}

// The walk's previous entry at or before j in `reach`, or 64: the backward replays a batch from
// its last entry to its first (uniform as `next_entry` is).
fn prev_entry(reach: vec2<u32>, j: u32) -> u32 {
    return subgroupBroadcastFirst(prev_in(reach.x, reach.y, j));
}

// The mask of the batch's entries (the first `batch` of `masks`) whose bit `block` is set, as
// (lo, hi); every entry when `one_block` is false (the subgroup spans several blocks).
fn reaching(batch: u32, block: u32, one_block: bool) -> vec2<u32> {
    if !one_block {
        return vec2<u32>(0xffffffffu);
    }
    var m = vec2<u32>(0u);
    for (var e = 0u; e < min(batch, 32u); e++) {
        m.x |= ((s_blocks[e] >> block) & 1u) << e;
    }
    for (var e = 32u; e < batch; e++) {
        m.y |= ((s_blocks[e] >> block) & 1u) << (e - 32u);
    }
    return m;
}
#endif

// The batch entry a subgroup of a backward pass replays before entry j (TILE_PIXELS when there is
// none): with the block walk the previous one that can reach the subgroup's block (the others
// have alpha -1 at all its pixels, so replaying them changes nothing), else j - 1. `reach` is
// `reaching`'s mask (any value without BLOCK_WALK).
fn entry_before(reach: vec2<u32>, j: u32) -> u32 {
    if j == 0u {
        return TILE_PIXELS;
    }
#ifdef BLOCK_WALK
    return prev_entry(reach, j - 1u);
#else
    return j - 1u;
#endif
}
