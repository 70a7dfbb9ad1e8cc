// Stage `rasterize`, pass 1 (twin: trgs_core::reference::rasterize): one workgroup per tile
// (TILE_PIXELS threads), one thread per pixel, the tile's depth-sorted Gaussians streamed through
// workgroup memory in batches of TILE_PIXELS, or with BLOCK_WALK read by each subgroup from the
// key list (shared/chunk_walk.wgsl). Two
// transmittances: primary Gaussians advance T_t (C_t, D_t, alpha) and T_m
// (the glass mask M, which they occlude but never paint); glass Gaussians advance only T_m and
// paint M. A primary Gaussian that would bring T_t below 1e-4 ends the pixel; one that would bring
// T_m below it ends M only. With DEPTH_VARIANCE, a second walk over the blended Gaussians gives
// V = sum w |z - D_t| (it needs the final D_t); without, V is written as zero.
#include "shared/common.wgsl"
#include "shared/raster_pages.wgsl"
#include "shared/splat.wgsl"
#include "shared/chunk_walk.wgsl"

@group(0) @binding(0) var<storage, read> params: RasterParams;
@group(0) @binding(1) var<storage, read> projected: array<ProjectedGaussian>;
@group(0) @binding(2) var<storage, read> values: array<u32>;
@group(0) @binding(3) var<storage, read> ranges: array<u32>;
// (C_t, 1 - T_t) per pixel.
@group(0) @binding(4) var<storage, read_write> transmission: array<vec4<f32>>;
// (D_t, V, M, 0) per pixel.
@group(0) @binding(5) var<storage, read_write> geometry: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> states: array<RasterState>;
#ifdef PAGED
// Projected records from index params.page on (shared/raster_pages.wgsl).
@group(0) @binding(7) var<storage, read> projected_hi: array<ProjectedGaussian>;
// Sorted key values from index params.key_page on.
@group(0) @binding(8) var<storage, read> values_hi: array<u32>;
#endif

// (mean, m, 1 for glass): the mask rides with the mean so that a step loads three vectors.
var<workgroup> s_mean: array<vec4<f32>, TILE_PIXELS>;
var<workgroup> s_conic: array<vec4<f32>, TILE_PIXELS>;
// (colour, depth)
var<workgroup> s_color: array<vec4<f32>, TILE_PIXELS>;
#ifndef BLOCK_WALK
// Pixels of the tile that have stopped (with BLOCK_WALK each subgroup stops on its own).
var<workgroup> num_done: atomic<u32>;
#endif
var<workgroup> max_last: atomic<u32>;
var<workgroup> num_walked: atomic<u32>;

// The pixel's state through the first walk (private, so that `step_entry` can step it).
var<private> pixel: vec2<f32>;
var<private> t: f32;
var<private> tm: f32;
var<private> m_active: bool;
var<private> color: vec3<f32>;
var<private> wsum: f32;
var<private> zsum: f32;
var<private> mask: f32;
var<private> last_t: u32;
var<private> last_m: u32;
var<private> done: bool;

// The entry of key index i (shared/block_walk.wgsl).
fn list_entry(i: u32) -> ChunkEntry {
    return pass1_entry(i);
}

// Batch `round` of the tile's list into workgroup memory (without BLOCK_WALK, and for the
// depth-variance walk).
fn load_batch(start: u32, end: u32, round: u32, lid: u32) {
    let idx = start + round * TILE_PIXELS + lid;
    if idx < end {
        let e = list_entry(idx);
        s_mean[lid] = e.mean;
        s_conic[lid] = e.conic;
        s_color[lid] = e.color;
    }
}

// List entry `li` (as load_batch keeps it) at this pixel, by pass 1's rules.
fn step_entry(g: ChunkEntry, li: u32) {
    if done {
        return;
    }
    let mean = g.mean;
    let c = g.color;
    let alpha = alpha_at(g.conic, pixel - mean.xy);
    if alpha < 0.0 {
        return;
    }
    if mean.w == 0.0 {
        let next_t = t * (1.0 - alpha);
        if next_t < MIN_TRANSMITTANCE {
            last_t = li;
            if m_active {
                last_m = li;
            }
            done = true;
#ifndef BLOCK_WALK
            atomicAdd(&num_done, 1u);
#endif
            return;
        }
        let wgt = alpha * t;
        color += c.xyz * wgt;
        wsum += wgt;
        zsum += c.w * wgt;
        t = next_t;
    }
    if m_active {
        let next_m = tm * (1.0 - alpha);
        if next_m < MIN_TRANSMITTANCE {
            m_active = false;
            last_m = li;
        } else {
            mask += mean.z * alpha * tm;
            tm = next_m;
        }
    }
}

// For shared/chunk_walk.wgsl: batch entry e, and whether this pixel has stopped.
#ifndef BLOCK_WALK
fn batch_entry(e: u32) -> ChunkEntry {
    return ChunkEntry(s_mean[e], s_conic[e], s_color[e], 0u);
}
#endif

fn walk_over() -> bool {
    return done;
}

// One workgroup per tile; its invocations are numbered as the tile's pixels are in `main`.
// (One-dimensional: a subgroup's lane id needs it.)
@compute @workgroup_size(TILE_PIXELS)
fn main(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
#ifdef BLOCK_WALK
    @builtin(subgroup_invocation_id) sg_lane: u32,
    @builtin(subgroup_size) sg_size: u32,
#endif
) {
    let tx = wid.x + params.tile_x0;
    let ty = wid.y + params.tile_y0;
    // Eight consecutive threads take a block of 4 x 2 pixels, not a row of 8: on a CPU adapter
    // they are one SIMD vector, which walks the list until its last pixel stops, and compact
    // blocks' pixels stop closer together, so more of the vector's steps do work. A GPU's
    // 32-thread warp still takes 8 x 4 pixels.
    let block = lid / 8u;
    let lane = lid % 8u;
    let x = tx * TILE_SIZE + (block % (TILE_SIZE / 4u)) * 4u + lane % 4u;
    let y = ty * TILE_SIZE + (block / (TILE_SIZE / 4u)) * 2u + lane / 4u;
    let inside = x < params.width && y < params.height;
    let tile = ty * params.tiles_x + tx;
    let start = ranges[2u * tile];
    let end = max(ranges[2u * tile + 1u], start);
    let n = end - start;
    let rounds = (n + TILE_PIXELS - 1u) / TILE_PIXELS;
    if lid == 0u {
#ifndef BLOCK_WALK
        atomicStore(&num_done, 0u);
#endif
        atomicStore(&max_last, 0u);
    }
    workgroupBarrier();
    done = !inside;
#ifndef BLOCK_WALK
    if done {
        atomicAdd(&num_done, 1u);
    }
#endif
    pixel = vec2<f32>(f32(x) + 0.5, f32(y) + 0.5);
    let corner = vec2<f32>(f32(tx * TILE_SIZE) + 0.5, f32(ty * TILE_SIZE) + 0.5);
#ifdef BLOCK_WALK
    // Whether this subgroup lies in one block (it does on lavapipe, where it is the block's SIMD
    // vector): only then may it skip the entries its block does not reach, all lanes together.
    let one_block = in_one_block(block);
#endif
    t = 1.0;
    tm = 1.0;
    m_active = true;
    color = vec3<f32>(0.0);
    wsum = 0.0;
    zsum = 0.0;
    mask = 0.0;
    last_t = n;
    last_m = n;
#ifdef BLOCK_WALK
    walk_list(start, n, BlockOf(corner, vec2<u32>(4u, 2u), block, one_block), sg_lane, sg_size);
#else
    for (var r = 0u; r < rounds; r++) {
        if workgroupUniformLoad(&num_done) == TILE_PIXELS {
            break;
        }
        load_batch(start, end, r, lid);
        workgroupBarrier();
        let batch = min(TILE_PIXELS, n - r * TILE_PIXELS);
        walk_batch(batch, r);
    }
#endif
    var depth = 0.0;
    if wsum > 0.0 {
        depth = zsum / wsum;
    }
    var variance = 0.0;
    var sign_sum = 0.0;
#ifdef DEPTH_VARIANCE
    // Second walk: the spread of the blended depths around D_t. The list is sorted by the depth
    // z that is blended, so the entries nearer than D_t come first, and since D_t is the
    // weighted mean, sum_{z > D} w (z - D) = sum_{z < D} w (D - z): V = 2 sum_{z < D} w (D - z)
    // and sum w sign(z - D) = W - W_{z = D} - 2 W_{z < D}. A pixel's walk ends at its first
    // entry deeper than D_t (or at last_t), often long before last_t on an opaque surface.
    if lid == 0u {
        atomicStore(&num_walked, 0u);
    }
    if inside {
        atomicMax(&max_last, last_t);
    }
    let walk = workgroupUniformLoad(&max_last);
    let walk_rounds = (walk + TILE_PIXELS - 1u) / TILE_PIXELS;
    var walked = !inside || wsum == 0.0;
    if walked {
        atomicAdd(&num_walked, 1u);
    }
    var tv = 1.0;
    var below = 0.0;
    var w_below = 0.0;
    var w_equal = 0.0;
    for (var r = 0u; r < walk_rounds; r++) {
        if workgroupUniformLoad(&num_walked) == TILE_PIXELS {
            break;
        }
        load_batch(start, end, r, lid);
        workgroupBarrier();
        let batch = min(TILE_PIXELS, n - r * TILE_PIXELS);
        for (var j = 0u; j < batch && !walked; j++) {
            let z = s_color[j].w;
            if r * TILE_PIXELS + j >= last_t || z > depth {
                walked = true;
                atomicAdd(&num_walked, 1u);
                break;
            }
            let mean = s_mean[j];
            if mean.w != 0.0 {
                continue;
            }
            let alpha = alpha_at(s_conic[j], pixel - mean.xy);
            if alpha < 0.0 {
                continue;
            }
            let wgt = alpha * tv;
            if z < depth {
                below += wgt * (depth - z);
                w_below += wgt;
            } else {
                w_equal += wgt;
            }
            tv *= 1.0 - alpha;
        }
    }
    if wsum > 0.0 {
        variance = 2.0 * below;
        sign_sum = wsum - w_equal - 2.0 * w_below;
    }
#endif
    if inside {
        let p = y * params.width + x;
        transmission[p] = vec4<f32>(color + t * params.background.xyz, 1.0 - t);
        geometry[p] = vec4<f32>(depth, variance, mask, 0.0);
        var s: RasterState;
        s.t_final = t;
        s.tm_final = tm;
        s.last_t = last_t;
        s.last_m = last_m;
        s.weight_sum = wsum;
        s.depth_sign_sum = sign_sum;
        states[p] = s;
    }
}
