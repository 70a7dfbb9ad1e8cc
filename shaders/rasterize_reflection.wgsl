// Stage `rasterize_reflection`, pass 2 (twin: trgs_core::reference::rasterize_reflection): the
// mirrored view of one plane, dispatched over the tiles of the plane's footprint only
// (tile_x0, tile_y0 is the footprint's corner), and within them only the pixels whose camera ray
// hits the plane's rectangle from the front: nothing else ever shows the reflection. One
// transmittance; writes (C_raw, A) with C_raw = sum c w and A = sum a w into the plane's slot.
// Other pixels keep the zeros the buffers were cleared to.
#include "shared/common.wgsl"
#include "shared/splat.wgsl"
#include "shared/plane_hit.wgsl"

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

var<workgroup> s_mean: array<vec2<f32>, TILE_PIXELS>;
var<workgroup> s_conic: array<vec4<f32>, TILE_PIXELS>;
// (colour, reflection intensity a)
var<workgroup> s_color: array<vec4<f32>, TILE_PIXELS>;
var<workgroup> num_done: atomic<u32>;

@compute @workgroup_size(TILE_SIZE, TILE_SIZE)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let tx = wid.x + params.tile_x0;
    let ty = wid.y + params.tile_y0;
    let x = tx * TILE_SIZE + lid % TILE_SIZE;
    let y = ty * TILE_SIZE + lid / TILE_SIZE;
    let inside = x < params.width && y < params.height
        && rectangle_hit(planes[params.slot], camera.origin.xyz, camera_ray(camera, x, y)) >= 0.0;
    let tile = params.tile_base + wid.y * params.tiles_w + wid.x;
    let start = ranges[2u * tile];
    let end = max(ranges[2u * tile + 1u], start);
    let n = end - start;
    let rounds = (n + TILE_PIXELS - 1u) / TILE_PIXELS;
    if lid == 0u {
        atomicStore(&num_done, 0u);
    }
    workgroupBarrier();
    var done = !inside;
    if done {
        atomicAdd(&num_done, 1u);
    }
    let pixel = vec2<f32>(f32(x) + 0.5, f32(y) + 0.5);
    var t = 1.0;
    var color = vec3<f32>(0.0);
    var intensity = 0.0;
    var last = n;
    for (var r = 0u; r < rounds; r++) {
        if workgroupUniformLoad(&num_done) == TILE_PIXELS {
            break;
        }
        let idx = start + r * TILE_PIXELS + lid;
        if idx < end {
            let g = projected[values[idx]];
            s_mean[lid] = g.mean2d;
            s_conic[lid] = g.conic;
            s_color[lid] = vec4<f32>(g.color.xyz, g.reflection);
        }
        workgroupBarrier();
        let batch = min(TILE_PIXELS, n - r * TILE_PIXELS);
        for (var j = 0u; j < batch && !done; j++) {
            let alpha = alpha_at(s_conic[j], pixel - s_mean[j]);
            if alpha < 0.0 {
                continue;
            }
            let next_t = t * (1.0 - alpha);
            if next_t < MIN_TRANSMITTANCE {
                last = r * TILE_PIXELS + j;
                done = true;
                atomicAdd(&num_done, 1u);
                break;
            }
            let wgt = alpha * t;
            color += s_color[j].xyz * wgt;
            intensity += s_color[j].w * wgt;
            t = next_t;
        }
    }
    if inside {
        let p = params.slot * params.width * params.height + y * params.width + x;
        reflection_raw[p] = vec4<f32>(color, intensity);
        var s: ReflectionState;
        s.t_final = t;
        s.last = last;
        states[p] = s;
    }
}
