// Stage `tile_counts` (twin: trgs_core::reference::tile_counts): how many tiles of the view's
// tile limit (the whole image, or a plane's footprint) each projected Gaussian touches.
#include "shared/common.wgsl"
#include "shared/tiles.wgsl"

@group(0) @binding(0) var<storage, read> tiles: TileParams;
@group(0) @binding(1) var<storage, read> projected: array<ProjectedGaussian>;
@group(0) @binding(2) var<storage, read_write> counts: array<u32>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = linear_index(gid, nwg, 256u);
    if i >= tiles.count {
        return;
    }
    let g = projected[i];
    var n = 0u;
    if is_visible(g) {
        let r = tile_rect(g, tiles);
        n = (r.z - r.x) * (r.w - r.y);
    }
    counts[i] = n;
}
