// Stage `rasterize_reflection_bwd`, the adjoint of pass 2 (twin:
// trgs_core::reference::rasterize_reflection_bwd): the back-to-front replay of rasterize_bwd with
// one transmittance, over the tiles of the plane's footprint (tile_x0, tile_y0 is its corner),
// each thread ROWS pixels of one column as in rasterize_bwd (the column's eight on CPU adapters,
// where a subgroup reduction is a loop over the lanes). Pixels whose ray misses the plane kept the
// cleared state (last = 0) and replay nothing. Adds each mirrored Gaussian's colour,
// reflection-intensity, opacity, 2D mean and conic gradients into `grads`
// (PROJECTED_GRAD_FLOATS per Gaussian), summed over the thread's pixels and then the subgroup,
// once per subgroup that touched it. With BLOCK_WALK a subgroup steps back only through the
// entries that can reach its block, by chunks of its lanes read from the key list
// (shared/chunk_replay.wgsl).
#include "shared/common.wgsl"
#include "shared/raster_pages.wgsl"
#include "shared/splat.wgsl"
#include "shared/accumulate.wgsl"
#include "shared/tile_rows.wgsl"
#include "shared/chunk_replay.wgsl"

@group(0) @binding(0) var<storage, read> params: RasterParams;
@group(0) @binding(1) var<storage, read> projected: array<ProjectedGaussian>;
@group(0) @binding(2) var<storage, read> values: array<u32>;
@group(0) @binding(3) var<storage, read> ranges: array<u32>;
// Plane slot params.slot of the per-plane states and of dL/d(C_raw, A) (after compose_bwd).
@group(0) @binding(4) var<storage, read> states: array<ReflectionState>;
@group(0) @binding(5) var<storage, read> g_reflection_raw: array<vec4<f32>>;
#ifdef FLOAT_ATOMICS
@group(0) @binding(6) var<storage, read_write> grads: array<atomic<f32>>;
#else
@group(0) @binding(6) var<storage, read_write> grads: array<atomic<u32>>;
#endif
#ifdef PAGED
// The records and gradients of the Gaussians from index params.page on, and the sorted
// key values from params.key_page on (shared/raster_pages.wgsl, shared/accumulate.wgsl).
@group(0) @binding(7) var<storage, read> projected_hi: array<ProjectedGaussian>;
#ifdef FLOAT_ATOMICS
@group(0) @binding(8) var<storage, read_write> grads_hi: array<atomic<f32>>;
#else
@group(0) @binding(8) var<storage, read_write> grads_hi: array<atomic<u32>>;
#endif
// Sorted key values from index params.key_page on.
@group(0) @binding(9) var<storage, read> values_hi: array<u32>;
#endif

#ifndef BLOCK_WALK
// A batch of list entries (`list_entry`'s fields).
var<workgroup> s_mean: array<vec2<f32>, TILE_PIXELS>;
var<workgroup> s_conic: array<vec4<f32>, TILE_PIXELS>;
var<workgroup> s_color: array<vec4<f32>, TILE_PIXELS>;
var<workgroup> s_index: array<u32, TILE_PIXELS>;
#endif

// One pixel's replay: what it read at the start and what it carries from entry to entry.
struct Pixel {
    last: u32,
    at: vec2<f32>,
    // dL/d(C_raw, A).
    gr: vec4<f32>,
    // The transmittance before the current entry and the suffix sum of dL/dalpha.
    t: f32,
    acc: f32,
}

fn start_pixel(x: u32, y: u32) -> Pixel {
    var px: Pixel;
    let inside = x < params.width && y < params.height;
    px.at = vec2<f32>(f32(x) + 0.5, f32(y) + 0.5);
    let p = select(0u, params.slot * params.width * params.height + y * params.width + x, inside);
    var st: ReflectionState;
    if inside {
        st = states[p];
    }
    px.last = st.last;
    px.gr = g_reflection_raw[p];
    px.t = st.t_final;
    return px;
}

// This thread's pixels (start_pixel), carried through the replay.
var<private> px: array<Pixel, ROWS>;

// For shared/chunk_replay.wgsl: the entry of key index i as pass 2 takes it
// (shared/block_walk.wgsl).
fn list_entry(i: u32) -> ChunkEntry {
    return pass2_entry(i);
}

#ifndef BLOCK_WALK
// For shared/chunk_replay.wgsl: a batch's slot written and read.
fn store_entry(slot: u32, e: ChunkEntry) {
    s_mean[slot] = e.mean.xy;
    s_conic[slot] = e.conic;
    s_color[slot] = e.color;
    s_index[slot] = e.index;
}

fn batch_entry(e: u32) -> ChunkEntry {
    return ChunkEntry(vec4<f32>(s_mean[e], 0.0, 0.0), s_conic[e], s_color[e], s_index[e]);
}
#endif

// Replays list entry `li` (`list_entry`'s fields: colour with the reflection intensity) at this
// thread's pixels, and adds the subgroup's gradients to the mirrored Gaussian's record. In
// uniform control flow: it ends with subgroup reductions.
fn replay_entry(entry: ChunkEntry, li: u32) {
    let mean = entry.mean.xy;
    let conic = entry.conic;
    let color = entry.color;
    var g: array<vec4<f32>, 3>;
    var blended = false;
    for (var k = 0u; k < ROWS; k++) {
        if li >= px[k].last {
            continue;
        }
        let dd = px[k].at - mean;
        let terms = alpha_terms(conic, dd);
        let alpha = terms.x;
        if alpha < 0.0 {
            continue;
        }
        blended = true;
        let ra = 1.0 / (1.0 - alpha);
        let tj = px[k].t * ra;
        let wgt = alpha * tj;
        let phi = dot(px[k].gr, color);
        g[2] += px[k].gr * wgt;
        let g_alpha = phi * tj - px[k].acc * ra;
        px[k].acc += phi * wgt;
        px[k].t = tj;
        let ga = alpha_bwd(conic, dd, terms, g_alpha);
        g[0] += ga[0];
        g[1] += ga[1];
    }
    if subgroup_any(blended) {
        accumulate_subgroup12(PROJECTED_GRAD_FLOATS * entry.index, g);
    }
}

// One workgroup per footprint tile, TILE_SIZE x TILE_SIZE / ROWS threads numbered row by row
// (one-dimensional: a subgroup's lane id needs it).
@compute @workgroup_size(TILE_PIXELS / ROWS)
fn main(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
#ifdef BLOCK_WALK
    @builtin(subgroup_invocation_id) sg_lane: u32,
    @builtin(subgroup_size) sg_size: u32,
#endif
) {
    let x = (wid.x + params.tile_x0) * TILE_SIZE + lid % TILE_SIZE;
    let y0 = (wid.y + params.tile_y0) * TILE_SIZE + (lid / TILE_SIZE) * ROWS;
    let tile = params.tile_base + wid.y * params.tiles_w + wid.x;
    let start = ranges[2u * tile];
    let end = max(ranges[2u * tile + 1u], start);
    var my_last = 0u;
    for (var k = 0u; k < ROWS; k++) {
        px[k] = start_pixel(x, y0 + k);
        my_last = max(my_last, px[k].last);
    }
    // The subgroup's own last entry: its lanes skip the entries none of them blended (a subgroup
    // runs its own trip count; on a CPU adapter it is one SIMD vector).
    let sg_last = subgroup_max(my_last);
#ifdef BLOCK_WALK
    let block = lid / 8u;
    let tile_px = vec2<u32>(wid.x + params.tile_x0, wid.y + params.tile_y0) * TILE_SIZE;
    let corner = vec2<f32>(tile_px) + 0.5;
    let b = BlockOf(corner, vec2<u32>(8u, ROWS), block, in_one_block(block));
    replay_list(start, sg_last, b, sg_lane, sg_size);
#else
    replay_batches(start, end, my_last, sg_last, lid);
#endif
}
