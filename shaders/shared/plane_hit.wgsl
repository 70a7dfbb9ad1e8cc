// Camera rays and ray-rectangle hits (twins: trgs_core::scene::Camera::pixel_ray and
// trgs_core::plane_math::ray_rectangle_hit), shared by `compose` and `rasterize_reflection` so
// that both decide a pixel's hit with the same arithmetic.

// Unit world-space direction of the ray through the centre of pixel (x, y).
fn camera_ray(cam: ComposeParams, x: u32, y: u32) -> vec3<f32> {
    let c = vec3<f32>(
        (f32(x) + 0.5 - cam.focal.z) / cam.focal.x,
        (f32(y) + 0.5 - cam.focal.w) / cam.focal.y,
        1.0,
    );
    let to_world = mat3x3<f32>(cam.cam_col0.xyz, cam.cam_col1.xyz, cam.cam_col2.xyz);
    return normalize(to_world * c);
}

// Ray parameter of the hit on the plane's rectangle from the front side, or -1.
fn rectangle_hit(plane: PlaneGpu, origin: vec3<f32>, dir: vec3<f32>) -> f32 {
    let n = plane.normal.xyz;
    let side = dot(origin - plane.centre.xyz, n);
    let toward = dot(dir, n);
    if !(side > 0.0) || !(toward < 0.0) {
        return -1.0;
    }
    let s = -side / toward;
    if !(s < 3.0e38) {
        return -1.0;
    }
    let local = origin + s * dir - plane.centre.xyz;
    let u = dot(local, plane.axis.xyz);
    let v = dot(local, plane.bitangent.xyz);
    if abs(u) <= plane.axis.w && abs(v) <= plane.bitangent.w {
        return s;
    }
    return -1.0;
}
