// Not a stage: a check kernel for the test that compares `draw_below` (shared/random.wgsl) with
// its twin `trgs_core::reference::draw_below`, bit for bit. The relocation tests cannot see an
// error of one in its product: a draw changes only where the uniform integer lands exactly on a
// cumulative weight. Thread j writes draw j at seed `seeds[j]` below `totals[j]`.
#include "shared/random.wgsl"

@group(0) @binding(0) var<storage, read> seeds: array<u32>;
@group(0) @binding(1) var<storage, read> totals: array<u32>;
@group(0) @binding(2) var<storage, read_write> draws: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let j = gid.x;
    if j < arrayLength(&draws) {
        draws[j] = draw_below(seeds[j], j, totals[j]);
    }
}
