// Stage `rasterize`, pass 1 (twin: trgs_core::reference::rasterize): one workgroup per tile
// (TILE_PIXELS threads), one thread per pixel, the tile's depth-sorted Gaussians streamed through
// workgroup memory in batches of TILE_PIXELS; with BLOCK_WALK each subgroup walks a batch in
// chunks of its lanes, by broadcasts (`walk_batch`). Two transmittances: primary Gaussians advance T_t (C_t, D_t, alpha) and T_m
// (the glass mask M, which they occlude but never paint); glass Gaussians advance only T_m and
// paint M. A primary Gaussian that would bring T_t below 1e-4 ends the pixel; one that would bring
// T_m below it ends M only. With DEPTH_VARIANCE, a second walk over the blended Gaussians gives
// V = sum w |z - D_t| (it needs the final D_t); without, V is written as zero.
#include "shared/common.wgsl"
#include "shared/raster_pages.wgsl"
#include "shared/splat.wgsl"
#include "shared/block_walk.wgsl"

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
#ifdef BLOCK_WALK
// The 4 x 2 blocks of the tile each entry can reach (block_reach).
var<workgroup> s_blocks: array<u32, TILE_PIXELS>;
#endif
var<workgroup> num_done: atomic<u32>;
var<workgroup> max_last: atomic<u32>;
var<workgroup> num_walked: atomic<u32>;

// The pixel's state through the first walk (private, so that `blend_entry` can step it).
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

fn load_batch(start: u32, end: u32, round: u32, lid: u32, corner: vec2<f32>) {
    let idx = start + round * TILE_PIXELS + lid;
    if idx < end {
        let g = projected_at(value_at(idx));
        s_mean[lid] = vec4<f32>(g.mean2d, g.mask, f32((g.flags & FLAG_GLASS) != 0u));
        s_conic[lid] = g.conic;
        s_color[lid] = g.color;
#ifdef BLOCK_WALK
        s_blocks[lid] = block_reach(g.conic, g.mean2d, corner, vec2<u32>(4u, 2u));
#endif
    }
}

// List entry `li` (mean, conic, colour as load_batch keeps them) at this pixel, by pass 1's rules.
fn blend_entry(mean: vec4<f32>, conic: vec4<f32>, c: vec4<f32>, li: u32) {
    if done {
        return;
    }
    let alpha = alpha_at(conic, pixel - mean.xy);
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
            atomicAdd(&num_done, 1u);
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

#ifdef BLOCK_WALK
// The batch's entries [0, batch) (round r) at this pixel, walked by the subgroup in chunks of
// its size: lane l reads entry first + l from workgroup memory, and the chunk's entries that
// reach the subgroup's block are then stepped through in order, each broadcast from its lane.
// On lavapipe every read of workgroup memory is a loop over the vector's lanes, and one read a
// lane per chunk replaces the three reads a step of a walk through workgroup memory made. A lane
// id is a constant of each broadcast (WGSL asks for a constant), so the chunk's steps are
// written out for subgroups of up to 8 lanes, which BLOCK_WALK's adapters have.
fn walk_batch(batch: u32, r: u32, block: u32, one_block: bool, lane: u32, size: u32) {
    for (var first = 0u; first < batch; first += size) {
        if subgroupAll(done) {
            break;
        }
        let e = first + lane;
        var mean = vec4<f32>(0.0);
        var conic = vec4<f32>(0.0);
        var c = vec4<f32>(0.0);
        var reaches = false;
        if e < batch {
            mean = s_mean[e];
            conic = s_conic[e];
            c = s_color[e];
            reaches = !one_block || ((s_blocks[e] >> block) & 1u) != 0u;
        }
        let reach = subgroupBallot(reaches).x;
        let li = r * TILE_PIXELS + first;
        if (reach & 1u) != 0u {
            blend_entry(subgroupBroadcast(mean, 0u), subgroupBroadcast(conic, 0u), subgroupBroadcast(c, 0u), li);
        }
        if (reach & 2u) != 0u {
            blend_entry(subgroupBroadcast(mean, 1u), subgroupBroadcast(conic, 1u), subgroupBroadcast(c, 1u), li + 1u);
        }
        if (reach & 4u) != 0u {
            blend_entry(subgroupBroadcast(mean, 2u), subgroupBroadcast(conic, 2u), subgroupBroadcast(c, 2u), li + 2u);
        }
        if (reach & 8u) != 0u {
            blend_entry(subgroupBroadcast(mean, 3u), subgroupBroadcast(conic, 3u), subgroupBroadcast(c, 3u), li + 3u);
        }
        if (reach & 16u) != 0u {
            blend_entry(subgroupBroadcast(mean, 4u), subgroupBroadcast(conic, 4u), subgroupBroadcast(c, 4u), li + 4u);
        }
        if (reach & 32u) != 0u {
            blend_entry(subgroupBroadcast(mean, 5u), subgroupBroadcast(conic, 5u), subgroupBroadcast(c, 5u), li + 5u);
        }
        if (reach & 64u) != 0u {
            blend_entry(subgroupBroadcast(mean, 6u), subgroupBroadcast(conic, 6u), subgroupBroadcast(c, 6u), li + 6u);
        }
        if (reach & 128u) != 0u {
            blend_entry(subgroupBroadcast(mean, 7u), subgroupBroadcast(conic, 7u), subgroupBroadcast(c, 7u), li + 7u);
        }
    }
}
#else
// The batch's entries [0, batch) (round r) at this pixel, one after another from workgroup
// memory.
fn walk_batch(batch: u32, r: u32) {
    for (var j = 0u; j < batch && !done; j++) {
        blend_entry(s_mean[j], s_conic[j], s_color[j], r * TILE_PIXELS + j);
    }
}
#endif

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
        atomicStore(&num_done, 0u);
        atomicStore(&max_last, 0u);
    }
    workgroupBarrier();
    done = !inside;
    if done {
        atomicAdd(&num_done, 1u);
    }
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
    for (var r = 0u; r < rounds; r++) {
        if workgroupUniformLoad(&num_done) == TILE_PIXELS {
            break;
        }
        load_batch(start, end, r, lid, corner);
        workgroupBarrier();
        let batch = min(TILE_PIXELS, n - r * TILE_PIXELS);
#ifdef BLOCK_WALK
        walk_batch(batch, r, block, one_block, sg_lane, sg_size);
#else
        walk_batch(batch, r);
#endif
    }
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
        load_batch(start, end, r, lid, corner);
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
