// Stage `tile_counts` (twin: trgs_core::reference::tile_counts): how many tiles of the view's
// tile limit (the whole image, or a plane's footprint) each projected Gaussian touches. One thread
// per Gaussian of project's candidate list (dispatched indirectly); the counts of the others,
// culled by project's cheap tests, stay at the zero they were cleared to.
#include "shared/common.wgsl"
#include "shared/tiles.wgsl"

@group(0) @binding(0) var<storage, read> tiles: TileParams;
@group(0) @binding(1) var<storage, read> projected: array<ProjectedGaussian>;
@group(0) @binding(2) var<storage, read_write> counts: array<u32>;
@group(0) @binding(3) var<storage, read> candidates: array<u32>;
@group(0) @binding(4) var<storage, read> work: array<u32, 4>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= work[3] {
        return;
    }
    let i = candidates[gid.x];
    let g = projected[i];
    var n = 0u;
    if is_visible(g) {
        let r = tile_rect(g, tiles);
        n = (r.z - r.x) * (r.w - r.y);
    }
    counts[i] = n;
}
