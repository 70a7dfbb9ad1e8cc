// The throughput baseline of the benchmarks (not a rendering stage): a trivial tiled splat loop.
// One workgroup per tile, one thread per pixel; every tile blends the same `params.slot`
// Gaussians, streamed through workgroup memory in batches of TILE_PIXELS, with no sorting, no early
// exit and a single transmittance. `rasterize`'s pixel-Gaussian evaluations per second are
// reported next to this loop's on the same adapter.
#include "shared/common.wgsl"
#include "shared/splat.wgsl"

@group(0) @binding(0) var<storage, read> params: RasterParams;
@group(0) @binding(1) var<storage, read> projected: array<ProjectedGaussian>;
@group(0) @binding(2) var<storage, read_write> out: array<vec4<f32>>;

var<workgroup> s_mean: array<vec2<f32>, TILE_PIXELS>;
var<workgroup> s_conic: array<vec4<f32>, TILE_PIXELS>;
var<workgroup> s_color: array<vec4<f32>, TILE_PIXELS>;

@compute @workgroup_size(TILE_SIZE, TILE_SIZE)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let x = wid.x * TILE_SIZE + lid % TILE_SIZE;
    let y = wid.y * TILE_SIZE + lid / TILE_SIZE;
    let pixel = vec2<f32>(f32(x) + 0.5, f32(y) + 0.5);
    let n = params.slot;
    var t = 1.0;
    var color = vec3<f32>(0.0);
    for (var start = 0u; start < n; start += TILE_PIXELS) {
        workgroupBarrier();
        if start + lid < n {
            let g = projected[start + lid];
            s_mean[lid] = g.mean2d;
            s_conic[lid] = g.conic;
            s_color[lid] = g.color;
        }
        workgroupBarrier();
        let batch = min(TILE_PIXELS, n - start);
        for (var j = 0u; j < batch; j++) {
            let alpha = alpha_at(s_conic[j], pixel - s_mean[j]);
            if alpha < 0.0 {
                continue;
            }
            color += s_color[j].xyz * alpha * t;
            t *= 1.0 - alpha;
        }
    }
    if x < params.width && y < params.height {
        out[y * params.width + x] = vec4<f32>(color, t);
    }
}
