// Stage `rasterize_bwd`, the adjoint of pass 1 (twin: trgs_core::reference::rasterize_bwd): one
// workgroup per tile, one thread per pixel, a back-to-front replay of the tile's list in
// batches of TILE_PIXELS from the last entry any pixel blended. Each pixel recovers its transmittances by
// division (T_j = T_{j+1} / (1 - alpha_j), alpha <= 0.99) from the final ones the forward kept,
// with the forward's skip and stop rules, and carries the suffix sums that dL/dalpha needs. Every
// batch entry's per-pixel gradients (colour, depth with the depth-variance term, mask value,
// opacity, 2D mean and conic) are summed over the subgroup and added to the Gaussian's record of
// `grads` (PROJECTED_GRAD_FLOATS per Gaussian) once per subgroup that touched it.
#include "shared/common.wgsl"
#include "shared/splat.wgsl"
#include "shared/accumulate.wgsl"

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

// (mean, m, 1 for glass), conic with opacity, (colour, depth), the Gaussian's index.
var<workgroup> s_mean: array<vec4<f32>, TILE_PIXELS>;
var<workgroup> s_conic: array<vec4<f32>, TILE_PIXELS>;
var<workgroup> s_color: array<vec4<f32>, TILE_PIXELS>;
var<workgroup> s_index: array<u32, TILE_PIXELS>;
var<workgroup> max_last: atomic<u32>;

@compute @workgroup_size(TILE_SIZE, TILE_SIZE)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let tx = wid.x;
    let ty = wid.y;
    let x = tx * TILE_SIZE + lid % TILE_SIZE;
    let y = ty * TILE_SIZE + lid / TILE_SIZE;
    let inside = x < params.width && y < params.height;
    let tile = ty * params.tiles_x + tx;
    let start = ranges[2u * tile];
    let end = max(ranges[2u * tile + 1u], start);
    if lid == 0u {
        atomicStore(&max_last, 0u);
    }
    workgroupBarrier();
    let p = select(0u, y * params.width + x, inside);
    var st: RasterState;
    if inside {
        st = states[p];
        atomicMax(&max_last, st.last_t);
    }
    let gc = g_transmission[p].xyz;
    let gg = g_geometry[p];
    let g_m = gg.z;
    var g_v = 0.0;
    if params.depth_variance != 0u {
        g_v = gg.y;
    }
    let d = geometry[p].x;
    // D_t = sum z w / sum w, and V depends on D_t too: dV/dD = -sum w sign(z - D).
    let g_d_total = gg.x - g_v * st.depth_sign_sum;
    var g_zsum = 0.0;
    var g_wsum = 0.0;
    if st.weight_sum > 0.0 {
        g_zsum = g_d_total / st.weight_sum;
        g_wsum = -g_d_total * d / st.weight_sum;
    }
    // T_final appears in alpha = 1 - T and in the background term of C_t.
    let g_tfinal = -g_transmission[p].w + dot(gc, params.background.xyz);
    var t = st.t_final;
    var acc_t = g_tfinal * st.t_final;
    var tm = st.tm_final;
    var acc_m = 0.0;
    let pixel = vec2<f32>(f32(x) + 0.5, f32(y) + 0.5);

    let last = workgroupUniformLoad(&max_last);
    // The subgroup's own last entry: its lanes skip the entries none of them blended (a subgroup
    // runs its own trip count; on a CPU adapter it is one SIMD vector).
    let sg_last = subgroup_max(st.last_t);
    let rounds = (last + TILE_PIXELS - 1u) / TILE_PIXELS;
    for (var rr = 0u; rr < rounds; rr++) {
        let r = rounds - 1u - rr;
        workgroupBarrier();
        let idx = start + r * TILE_PIXELS + lid;
        if idx < end {
            let gi = values[idx];
            let g = projected[gi];
            s_mean[lid] = vec4<f32>(g.mean2d, g.mask, f32((g.flags & FLAG_GLASS) != 0u));
            s_conic[lid] = g.conic;
            s_color[lid] = g.color;
            s_index[lid] = gi;
        }
        workgroupBarrier();
        let batch = min(TILE_PIXELS, last - r * TILE_PIXELS);
        // Entries [0, mine) of this batch come before the subgroup's last.
        let mine = min(batch, sg_last - min(sg_last, r * TILE_PIXELS));
        for (var jj = batch - mine; jj < batch; jj++) {
            let j = batch - 1u - jj;
            let li = r * TILE_PIXELS + j;
            var g: array<vec4<f32>, 3>;
            var blended = false;
            if inside && li < st.last_t {
                let mean = s_mean[j];
                let conic = s_conic[j];
                let dd = pixel - mean.xy;
                let terms = alpha_terms(conic, dd);
                let alpha = terms.x;
                if alpha >= 0.0 {
                    blended = true;
                    // 1 / (1 - alpha) recovers each transmittance before this Gaussian.
                    let ra = 1.0 / (1.0 - alpha);
                    let glass = mean.w != 0.0;
                    var g_alpha = 0.0;
                    if !glass {
                        let tj = t * ra;
                        let wgt = alpha * tj;
                        let z = s_color[j].w;
                        let dz = z - d;
                        let phi = dot(gc, s_color[j].xyz) + g_zsum * z + g_wsum + g_v * abs(dz);
                        g[2] = vec4<f32>(gc * wgt, 0.0);
                        g[0].w = g_zsum * wgt + g_v * wgt * sign(dz);
                        g_alpha += phi * tj - acc_t * ra;
                        acc_t += phi * wgt;
                        t = tj;
                    }
                    if li < st.last_m {
                        let tmj = tm * ra;
                        var psi = 0.0;
                        if glass {
                            psi = g_m * mean.z;
                            g[1].w = g_m * alpha * tmj;
                        }
                        g_alpha += psi * tmj - acc_m * ra;
                        acc_m += psi * alpha * tmj;
                        tm = tmj;
                    }
                    let ga = alpha_bwd(conic, dd, terms, g_alpha);
                    g[0] = vec4<f32>(ga[0].xyz, g[0].w);
                    g[1] = vec4<f32>(ga[1].xyz, g[1].w);
                }
            }
            if subgroup_any(blended) {
                accumulate_subgroup12(PROJECTED_GRAD_FLOATS * s_index[j], g);
            }
        }
    }
}
