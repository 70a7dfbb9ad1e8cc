// Stage `gather_rows` (twins: trgs_core::scene::Gaussians::gather for the parameters,
// trgs_train::densify::RowPlan::apply for them and the Adam moments): output row j of a
// per-Gaussian buffer becomes a copy of source row sources[j], or zero when that index carries
// GATHER_ZERO and `honour_zero` is set (moments that restart). Densification rebuilds every
// attribute and moment buffer this way on the GPU, so that only the few attributes its decisions
// read cross to the CPU. One thread per output row; words are copied as bits (f32 and u32 alike).
// A buffer larger than one binding is gathered in (output range, source range) pairs: each
// dispatch copies the rows whose source lies in its bound source range, and writes the zero rows
// only in the dispatch of the first source range. With `given_rows`, a second pass over a
// gathered buffer writes only the rows marked GATHER_ZERO (those the plan makes anew), each
// from the same row of the plan's given values: the kept rows stay copies of their sources as
// they are when the plan is applied, which may be a step after it was decided.
#include "shared/common.wgsl"

@group(0) @binding(0) var<storage, read> params: GatherParams;
@group(0) @binding(1) var<storage, read> sources: array<u32>;
@group(0) @binding(2) var<storage, read> src: array<u32>;
@group(0) @binding(3) var<storage, read_write> dst: array<u32>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let row = linear_index(gid, nwg, 256u);
    if row >= params.count {
        return;
    }
    let source = sources[row];
    let anew = (source & GATHER_ZERO) != 0u;
    let out = row * params.width;
    if params.given_rows != 0u && !anew {
        return;
    }
    if params.honour_zero != 0u && anew {
        if params.first_source == 0u {
            for (var k = 0u; k < params.width; k++) {
                dst[out + k] = 0u;
            }
        }
        return;
    }
    let s = select(source & ~GATHER_ZERO, params.first_row + row, params.given_rows != 0u);
    if s < params.first_source || s - params.first_source >= params.source_rows {
        return;
    }
    let first = (s - params.first_source) * params.width;
    for (var k = 0u; k < params.width; k++) {
        dst[out + k] = src[first + k];
    }
}
