// Stage `rasterize_reflection`, pass 2 (twin: trgs_core::reference::rasterize_reflection): the
// mirrored view of one plane, dispatched over the tiles of the plane's footprint only
// (tile_x0, tile_y0 is the footprint's corner), and within them only the pixels whose camera ray
// hits the plane's rectangle from the front: nothing else ever shows the reflection. One
// transmittance; writes (C_raw, A) with C_raw = sum c w and A = sum a w into the plane's slot.
// Other pixels keep the zeros the buffers were cleared to.
#include "shared/common.wgsl"
#include "shared/raster_pages.wgsl"
#include "shared/splat.wgsl"
#include "shared/plane_hit.wgsl"
// ROWS pixels per thread (four rows on CPU adapters, where they are faster: `bench`).
#include "shared/tile_rows.wgsl"
#include "shared/chunk_walk.wgsl"

@group(0) @binding(0) var<storage, read> params: RasterParams;
@group(0) @binding(1) var<storage, read> projected: array<ProjectedGaussian>;
@group(0) @binding(2) var<storage, read> values: array<u32>;
@group(0) @binding(3) var<storage, read> ranges: array<u32>;
// (C_raw, A) per pixel of every plane, plane k at [k * pixels, (k + 1) * pixels).
@group(0) @binding(4) var<storage, read_write> reflection_raw: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> states: array<ReflectionState>;
// The camera's rays, and the planes (this pass's plane is planes[params.slot]).
@group(0) @binding(6) var<storage, read> camera: ComposeParams;
@group(0) @binding(7) var<storage, read> planes: array<PlaneGpu>;
#ifdef PAGED
// Projected records from index params.page on (shared/raster_pages.wgsl).
@group(0) @binding(8) var<storage, read> projected_hi: array<ProjectedGaussian>;
// Sorted key values from index params.key_page on.
@group(0) @binding(9) var<storage, read> values_hi: array<u32>;
#endif

#ifndef BLOCK_WALK
// A batch of list entries (`list_entry`'s fields).
var<workgroup> s_mean: array<vec2<f32>, TILE_PIXELS>;
var<workgroup> s_conic: array<vec4<f32>, TILE_PIXELS>;
var<workgroup> s_color: array<vec4<f32>, TILE_PIXELS>;
var<workgroup> num_done: atomic<u32>;
#endif

// One pixel's walk: where it is, what it has blended and where it stopped.
struct Pixel {
    inside: bool,
    done: bool,
    at: vec2<f32>,
    t: f32,
    color: vec3<f32>,
    intensity: f32,
    last: u32,
}

// This thread's pixels through the walk, and how many of them still blend (`active` is a
// reserved word in WGSL).
var<private> px: array<Pixel, ROWS>;
var<private> awake: u32;

// List entry `li` (as the batch keeps it: colour with the reflection intensity) at this
// thread's pixels.
fn step_entry(g: ChunkEntry, li: u32) {
    let mean = g.mean.xy;
    let conic = g.conic;
    let c = g.color;
    for (var k = 0u; k < ROWS; k++) {
        if px[k].done {
            continue;
        }
        let alpha = alpha_at(conic, px[k].at - mean);
        if alpha < 0.0 {
            continue;
        }
        let next_t = px[k].t * (1.0 - alpha);
        if next_t < MIN_TRANSMITTANCE {
            px[k].last = li;
            px[k].done = true;
            awake -= 1u;
#ifndef BLOCK_WALK
            atomicAdd(&num_done, 1u);
#endif
            continue;
        }
        let wgt = alpha * px[k].t;
        px[k].color += c.xyz * wgt;
        px[k].intensity += c.w * wgt;
        px[k].t = next_t;
    }
}

// For shared/chunk_walk.wgsl: the entry of key index i (its mean, conic with opacity, colour
// with the reflection intensity a), batch entry e, and whether this thread's pixels have
// stopped.
fn list_entry(i: u32) -> ChunkEntry {
    return pass2_entry(i);
}

#ifndef BLOCK_WALK
fn batch_entry(e: u32) -> ChunkEntry {
    return ChunkEntry(vec4<f32>(s_mean[e], 0.0, 0.0), s_conic[e], s_color[e], 0u);
}
#endif

fn walk_over() -> bool {
    return awake == 0u;
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
    let tx = wid.x + params.tile_x0;
    let ty = wid.y + params.tile_y0;
    let x = tx * TILE_SIZE + lid % TILE_SIZE;
    let y0 = ty * TILE_SIZE + (lid / TILE_SIZE) * ROWS;
    let tile = params.tile_base + wid.y * params.tiles_w + wid.x;
    let start = ranges[2u * tile];
    let end = max(ranges[2u * tile + 1u], start);
    let n = end - start;
    awake = 0u;
    for (var k = 0u; k < ROWS; k++) {
        let y = y0 + k;
        px[k].inside = x < params.width && y < params.height
            && rectangle_hit(planes[params.slot], camera.origin.xyz, camera_ray(camera, x, y)) >= 0.0;
        px[k].done = !px[k].inside;
        px[k].at = vec2<f32>(f32(x) + 0.5, f32(y) + 0.5);
        px[k].t = 1.0;
        px[k].last = n;
        if px[k].inside {
            awake += 1u;
        }
    }
#ifdef BLOCK_WALK
    let block = lid / 8u;
    let corner = vec2<f32>(f32(tx * TILE_SIZE) + 0.5, f32(ty * TILE_SIZE) + 0.5);
    // Whether this subgroup lies in one block (see shared/block_walk.wgsl).
    let b = BlockOf(corner, vec2<u32>(8u, ROWS), block, in_one_block(block));
    walk_list(start, n, b, sg_lane, sg_size);
#else
    if lid == 0u {
        atomicStore(&num_done, 0u);
    }
    workgroupBarrier();
    atomicAdd(&num_done, ROWS - awake);
    let rounds = (n + TILE_PIXELS - 1u) / TILE_PIXELS;
    for (var r = 0u; r < rounds; r++) {
        if workgroupUniformLoad(&num_done) == TILE_PIXELS {
            break;
        }
        for (var q = 0u; q < ROWS; q++) {
            let slot = lid + q * THREADS;
            let idx = start + r * TILE_PIXELS + slot;
            if idx < end {
                let e = list_entry(idx);
                s_mean[slot] = e.mean.xy;
                s_conic[slot] = e.conic;
                s_color[slot] = e.color;
            }
        }
        workgroupBarrier();
        let batch = min(TILE_PIXELS, n - r * TILE_PIXELS);
        walk_batch(batch, r);
    }
#endif
    for (var k = 0u; k < ROWS; k++) {
        if px[k].inside {
            let y = y0 + k;
            let p = params.slot * params.width * params.height + y * params.width + x;
            reflection_raw[p] = vec4<f32>(px[k].color, px[k].intensity);
            var s: ReflectionState;
            s.t_final = px[k].t;
            s.last = px[k].last;
            states[p] = s;
        }
    }
}
