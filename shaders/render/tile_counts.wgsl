// Stage `tile_counts` (twin: trgs_core::reference::tile_counts): how many tiles of the view's
// tile limit (the whole image, or a plane's footprint) each projected Gaussian touches. One thread
// per Gaussian of project's candidate list (dispatched indirectly); the counts of the others,
// culled by project's cheap tests, stay at the zero they were cleared to.
//
// A Gaussian that touches a tile is also an entry of the frame's depth order (stage
// `depth_order`), numbered `entry_base` + its index: its depth key, tile rectangle and a
// presence bit are kept per entry, and its count is added to the view's key total.
#include "shared/common.wgsl"
#include "shared/tiles.wgsl"

@group(0) @binding(0) var<storage, read> tiles: TileParams;
@group(0) @binding(1) var<storage, read> projected: array<ProjectedGaussian>;
@group(0) @binding(2) var<storage, read_write> counts: array<u32>;
@group(0) @binding(3) var<storage, read> candidates: array<u32>;
@group(0) @binding(4) var<storage, read> work: array<u32, 4>;
// Per entry: the tile rectangle, (x0 | y0 << 16, x1 | y1 << 16); its depth-order key; and a
// bit set when the Gaussian touches a tile (entry e: bit e % 32 of word e / 32, cleared before).
@group(0) @binding(5) var<storage, read_write> rects: array<vec2<u32>>;
@group(0) @binding(6) var<storage, read_write> depths: array<u32>;
@group(0) @binding(7) var<storage, read_write> present: array<atomic<u32>>;
// Per view: its key total as two words, the low 32 bits and the carries out of them (a total
// of 2^32 keys or more is refused, not wrapped).
@group(0) @binding(8) var<storage, read_write> key_totals: array<atomic<u32>>;

// The depth-order key (twin: reference::depth_key): the depth's f32 bits counted from `base`,
// the near plane's; DEPTH_KEY_BITS bits, so that `depth_order` sorts them in one radix pass
// fewer than the raw 32 bits.
fn depth_key(depth: f32, base: u32) -> u32 {
    let bits = bitcast<u32>(depth);
    if bits >= 0x80000000u {
        return 0u;
    }
    let max_key = (1u << DEPTH_KEY_BITS) - 1u;
    return min(select(0u, bits - base, bits > base), max_key);
}

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= work[3] {
        return;
    }
    let i = candidates[gid.x];
    let g = projected[i];
    var n = 0u;
    var r = vec4<u32>(0u);
    if is_visible(g) {
        r = tile_rect(g, tiles);
        n = (r.z - r.x) * (r.w - r.y);
    }
    counts[i] = n;
    if n == 0u {
        return;
    }
    let entry = tiles.entry_base + tiles.first + i;
    rects[entry] = vec2<u32>(r.x | (r.y << 16u), r.z | (r.w << 16u));
    depths[entry] = depth_key(g.color.w, tiles.depth_base);
    atomicOr(&present[entry / 32u], 1u << (entry % 32u));
    let before = atomicAdd(&key_totals[2u * tiles.view], n);
    if before > 0xffffffffu - n {
        atomicAdd(&key_totals[2u * tiles.view + 1u], 1u);
    }
}
