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
