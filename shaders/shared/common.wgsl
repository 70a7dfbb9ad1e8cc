// Helpers shared by every stage. The constants (TILE_SIZE, MAX_ALPHA, ...) and the GPU structs
// come from the prelude that trgs-render generates from its Rust definitions (one source of
// truth); see crates/trgs-render/src/layout.rs.

// Linear invocation index of a 1D dispatch that may have been split into 2D (more than 65,535
// workgroups) with `workgroup_size` threads per group.
fn linear_index(gid: vec3<u32>, nwg: vec3<u32>, workgroup_size: u32) -> u32 {
    return gid.x + gid.y * nwg.x * workgroup_size;
}

fn sigmoid(x: f32) -> f32 {
    return 1.0 / (1.0 + exp(-x));
}
