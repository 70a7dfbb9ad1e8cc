// Helpers shared by every stage. The constants (TILE_SIZE, MAX_ALPHA, ...) and the GPU structs
// come from the prelude that trgs-render generates from its Rust definitions (one source of
// truth); see crates/trgs-render/src/toolkit/layout.rs.

// Linear invocation index of a 1D dispatch that may have been split into 2D (more than 65,535
// workgroups) with `workgroup_size` threads per group.
fn linear_index(gid: vec3<u32>, nwg: vec3<u32>, workgroup_size: u32) -> u32 {
    return gid.x + gid.y * nwg.x * workgroup_size;
}

// The block that workgroup `wid` of a 1D dispatch (split into rows of `nwg.x` past 65,535
// workgroups) takes: a permutation of the workgroups that steps through the blocks by `step`,
// coprime to the spread dimension's size (trgs_render::gpu::spread_step says why; 0: no
// permutation). A split dispatch spreads its rows, not the blocks within a row. (n is at most
// 65,535, a dispatch dimension's limit, so w step fits in 32 bits.)
fn spread_block(wid: vec3<u32>, nwg: vec3<u32>, step: u32) -> u32 {
    if step == 0u {
        return wid.x + wid.y * nwg.x;
    }
    if nwg.y == 1u {
        return (wid.x * step) % nwg.x;
    }
    return ((wid.y * step) % nwg.y) * nwg.x + wid.x;
}

// The first block of workgroup `wid` in a strided dispatch (trgs_render::gpu::strided_grid) and
// the stride between its blocks: the dispatch's workgroups.
fn strided_first(wid: vec3<u32>, nwg: vec3<u32>) -> u32 {
    return wid.x + wid.y * nwg.x;
}

fn strided_step(nwg: vec3<u32>) -> u32 {
    return nwg.x * nwg.y;
}

// Blocks of `size` items that hold `count` items.
fn blocks_of(count: u32, size: u32) -> u32 {
    return count / size + select(0u, 1u, count % size != 0u);
}

fn sigmoid(x: f32) -> f32 {
    return 1.0 / (1.0 + exp(-x));
}

// Rotation matrix of the normalised quaternion (w, x, y, z), by columns.
fn quat_to_mat(q: vec4<f32>) -> mat3x3<f32> {
    let qn = q / sqrt(dot(q, q));
    let w = qn.x;
    let x = qn.y;
    let y = qn.z;
    let z = qn.w;
    return mat3x3<f32>(
        vec3<f32>(1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + w * z), 2.0 * (x * z - w * y)),
        vec3<f32>(2.0 * (x * y - w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z + w * x)),
        vec3<f32>(2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y)),
    );
}
