// Stage `rasterize_bwd`, the adjoint of pass 1 (twin: trgs_core::reference::rasterize_bwd): one
// workgroup per tile, each thread ROWS pixels of one column (ROWS consecutive rows), a
// back-to-front replay of the tile's list from the last entry any pixel of the subgroup (with
// BLOCK_WALK) or of the tile (in batches of TILE_PIXELS) blended. Each pixel recovers its transmittances by division (T_j = T_{j+1} / (1 -
// alpha_j), alpha <= 0.99) from the final ones the forward kept, with the forward's skip and
// stop rules, and carries the suffix sums that dL/dalpha needs. Every batch entry's per-pixel
// gradients (colour, depth with the depth-variance term, mask value, opacity, 2D mean and conic)
// are summed over the thread's pixels, then over the subgroup, and added to the Gaussian's
// record of `grads` (PROJECTED_GRAD_FLOATS per Gaussian) once per subgroup that touched it.
// With one pixel per thread on a CPU adapter those reductions and atomics take most of the
// kernel's time; with a tile column of eight rows per thread one of them serves the tile's 64
// pixels instead of 8.
// With BLOCK_WALK a subgroup steps back only through the entries that can reach its block
// (shared/block_walk.wgsl), by chunks of its lanes read from the key list (`replay_list`);
// without it the workgroup replays batches it loads into workgroup memory.
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
@group(0) @binding(4) var<storage, read> states: array<RasterState>;
// Forward (D_t, V, M, 0): D_t enters the depth-variance term.
@group(0) @binding(5) var<storage, read> geometry: array<vec4<f32>>;
// Total gradients of pass 1's layers (after compose_bwd): dL/d(C_t, alpha), dL/d(D_t, V, M, -).
@group(0) @binding(6) var<storage, read> g_transmission: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read> g_geometry: array<vec4<f32>>;
#ifdef FLOAT_ATOMICS
@group(0) @binding(8) var<storage, read_write> grads: array<atomic<f32>>;
#else
@group(0) @binding(8) var<storage, read_write> grads: array<atomic<u32>>;
#endif
#ifdef PAGED
// The records and gradients of the Gaussians from index params.page on, and the sorted
// key values from params.key_page on (shared/raster_pages.wgsl, shared/accumulate.wgsl).
@group(0) @binding(9) var<storage, read> projected_hi: array<ProjectedGaussian>;
#ifdef FLOAT_ATOMICS
@group(0) @binding(10) var<storage, read_write> grads_hi: array<atomic<f32>>;
#else
@group(0) @binding(10) var<storage, read_write> grads_hi: array<atomic<u32>>;
#endif
// Sorted key values from index params.key_page on.
@group(0) @binding(11) var<storage, read> values_hi: array<u32>;
#endif

#ifndef BLOCK_WALK
// A batch of list entries (`list_entry`'s fields).
var<workgroup> s_mean: array<vec4<f32>, TILE_PIXELS>;
var<workgroup> s_conic: array<vec4<f32>, TILE_PIXELS>;
var<workgroup> s_color: array<vec4<f32>, TILE_PIXELS>;
var<workgroup> s_index: array<u32, TILE_PIXELS>;
#endif

// One pixel's replay: what it read at the start and what it carries from entry to entry.
struct Pixel {
    inside: bool,
    last_t: u32,
    last_m: u32,
    at: vec2<f32>,
    // dL/dC_t, dL/dM, dL/dV, D_t, and dL/d(sum z w), dL/d(sum w) of D_t = sum z w / sum w.
    gc: vec3<f32>,
    g_m: f32,
    g_v: f32,
    d: f32,
    g_zsum: f32,
    g_wsum: f32,
    // The transmittances before the current entry and the suffix sums of dL/dalpha.
    t: f32,
    acc_t: f32,
    tm: f32,
    acc_m: f32,
}

fn start_pixel(x: u32, y: u32) -> Pixel {
    var px: Pixel;
    px.inside = x < params.width && y < params.height;
    px.at = vec2<f32>(f32(x) + 0.5, f32(y) + 0.5);
    let p = select(0u, y * params.width + x, px.inside);
    var st: RasterState;
    if px.inside {
        st = states[p];
    }
    px.last_t = st.last_t;
    px.last_m = st.last_m;
    px.gc = g_transmission[p].xyz;
    let gg = g_geometry[p];
    px.g_m = gg.z;
    if params.depth_variance != 0u {
        px.g_v = gg.y;
    }
    px.d = geometry[p].x;
    // D_t = sum z w / sum w, and V depends on D_t too: dV/dD = -sum w sign(z - D).
    let g_d_total = gg.x - px.g_v * st.depth_sign_sum;
    if st.weight_sum > 0.0 {
        px.g_zsum = g_d_total / st.weight_sum;
        px.g_wsum = -g_d_total * px.d / st.weight_sum;
    }
    // T_final appears in alpha = 1 - T and in the background term of C_t.
    let g_tfinal = -g_transmission[p].w + dot(px.gc, params.background.xyz);
    px.t = st.t_final;
    px.acc_t = g_tfinal * st.t_final;
    px.tm = st.tm_final;
    return px;
}

// This thread's pixels (start_pixel), carried through the replay.
var<private> px: array<Pixel, ROWS>;

// Replays list entry `li` (`list_entry`'s fields) at this thread's pixels, and adds the
// subgroup's gradients to the Gaussian's record. In uniform control flow: it ends with subgroup
// reductions.
fn replay_entry(entry: ChunkEntry, li: u32) {
    let mean = entry.mean;
    let conic = entry.conic;
    let color = entry.color;
    let glass = mean.w != 0.0;
    var g: array<vec4<f32>, 3>;
    var blended = false;
    for (var k = 0u; k < ROWS; k++) {
        if !px[k].inside || li >= px[k].last_t {
            continue;
        }
        let dd = px[k].at - mean.xy;
        let terms = alpha_terms(conic, dd);
        let alpha = terms.x;
        if alpha < 0.0 {
            continue;
        }
        blended = true;
        // 1 / (1 - alpha) recovers each transmittance before this Gaussian.
        let ra = 1.0 / (1.0 - alpha);
        var g_alpha = 0.0;
        if !glass {
            let tj = px[k].t * ra;
            let wgt = alpha * tj;
            let z = color.w;
            let dz = z - px[k].d;
            let phi = dot(px[k].gc, color.xyz) + px[k].g_zsum * z + px[k].g_wsum
                + px[k].g_v * abs(dz);
            g[2] += vec4<f32>(px[k].gc * wgt, 0.0);
            g[0].w += px[k].g_zsum * wgt + px[k].g_v * wgt * sign(dz);
            g_alpha += phi * tj - px[k].acc_t * ra;
            px[k].acc_t += phi * wgt;
            px[k].t = tj;
        }
        if li < px[k].last_m {
            let tmj = px[k].tm * ra;
            var psi = 0.0;
            if glass {
                psi = px[k].g_m * mean.z;
                g[1].w += px[k].g_m * alpha * tmj;
            }
            g_alpha += psi * tmj - px[k].acc_m * ra;
            px[k].acc_m += psi * alpha * tmj;
            px[k].tm = tmj;
        }
        let ga = alpha_bwd(conic, dd, terms, g_alpha);
        g[0] += vec4<f32>(ga[0].xyz, 0.0);
        g[1] += vec4<f32>(ga[1].xyz, 0.0);
    }
    if subgroup_any(blended) {
        accumulate_subgroup12(PROJECTED_GRAD_FLOATS * entry.index, g);
    }
}

// For shared/chunk_replay.wgsl: the entry of key index i as pass 1 takes it
// (shared/block_walk.wgsl).
fn list_entry(i: u32) -> ChunkEntry {
    return pass1_entry(i);
}

#ifndef BLOCK_WALK
// For shared/chunk_replay.wgsl: a batch's slot written and read.
fn store_entry(slot: u32, e: ChunkEntry) {
    s_mean[slot] = e.mean;
    s_conic[slot] = e.conic;
    s_color[slot] = e.color;
    s_index[slot] = e.index;
}

fn batch_entry(e: u32) -> ChunkEntry {
    return ChunkEntry(s_mean[e], s_conic[e], s_color[e], s_index[e]);
}
#endif

// One workgroup per tile, TILE_SIZE x TILE_SIZE / ROWS threads numbered row by row (one-
// dimensional: a subgroup's lane id needs it).
@compute @workgroup_size(TILE_PIXELS / ROWS)
fn main(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
#ifdef BLOCK_WALK
    @builtin(subgroup_invocation_id) sg_lane: u32,
    @builtin(subgroup_size) sg_size: u32,
#endif
) {
    let x = wid.x * TILE_SIZE + lid % TILE_SIZE;
    let y0 = wid.y * TILE_SIZE + (lid / TILE_SIZE) * ROWS;
    let tile = wid.y * params.tiles_x + wid.x;
    let start = ranges[2u * tile];
    let end = max(ranges[2u * tile + 1u], start);
    var my_last = 0u;
    for (var k = 0u; k < ROWS; k++) {
        px[k] = start_pixel(x, y0 + k);
        my_last = max(my_last, px[k].last_t);
    }
    // The subgroup's own last entry: its lanes skip the entries none of them blended (a subgroup
    // runs its own trip count; on a CPU adapter it is one SIMD vector).
    let sg_last = subgroup_max(my_last);
#ifdef BLOCK_WALK
    let block = lid / 8u;
    let corner = vec2<f32>(f32(wid.x * TILE_SIZE) + 0.5, f32(wid.y * TILE_SIZE) + 0.5);
    let b = BlockOf(corner, vec2<u32>(8u, ROWS), block, in_one_block(block));
    replay_list(start, sg_last, b, sg_lane, sg_size);
#else
    replay_batches(start, end, my_last, sg_last, lid);
#endif
}
