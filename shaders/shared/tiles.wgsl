// The tiles a projected Gaussian touches (twin: trgs_core::reference::tile_rect). Evaluated in
// f32 exactly as the CPU twin does, so binning matches bit for bit.

// Inclusive range of pixels along one axis whose centres (p + 0.5) lie in
// [centre - half, centre + half], clipped to [0, size); z = 0 when empty.
fn pixel_span(centre: f32, half: f32, size: u32) -> vec3<u32> {
    let lo = ceil(centre - half - 0.5);
    let hi = floor(centre + half - 0.5);
    let max_px = f32(size - 1u);
    // Written so that NaN falls through to "empty".
    if !(lo <= hi && hi >= 0.0 && lo <= max_px) {
        return vec3<u32>(0u, 0u, 0u);
    }
    return vec3<u32>(u32(max(lo, 0.0)), u32(min(hi, max_px)), 1u);
}

// Half-open tile rectangle (x0, y0, x1, y1) of a Gaussian, intersected with `limit`;
// (0, 0, 0, 0) when empty.
fn tile_rect(g: ProjectedGaussian, t: TileParams) -> vec4<u32> {
    return tile_rect_of(g.mean2d, g.extent, t.width, t.height, t.limit);
}

fn tile_rect_of(mean2d: vec2<f32>, extent: vec2<f32>, width: u32, height: u32, limit: vec4<u32>) -> vec4<u32> {
    let sx = pixel_span(mean2d.x, extent.x, width);
    let sy = pixel_span(mean2d.y, extent.y, height);
    if sx.z == 0u || sy.z == 0u {
        return vec4<u32>(0u);
    }
    let x0 = max(sx.x / TILE_SIZE, limit.x);
    let y0 = max(sy.x / TILE_SIZE, limit.y);
    let x1 = min(sx.y / TILE_SIZE + 1u, limit.z);
    let y1 = min(sy.y / TILE_SIZE + 1u, limit.w);
    if x0 >= x1 || y0 >= y1 {
        return vec4<u32>(0u);
    }
    return vec4<u32>(x0, y0, x1, y1);
}

fn is_visible(g: ProjectedGaussian) -> bool {
    return (g.flags & FLAG_VISIBLE) != 0u;
}
