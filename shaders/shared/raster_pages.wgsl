// What the rasterize kernels bind in pages of one binding each (toolkit::paged): a view's
// projected Gaussians, and the frame's sorted key values. With PAGED (the kernels' variant for a
// frame with a second page of either) the first `params.page` records are in `projected`, the
// rest in `projected_hi`, and the first `params.key_page` values in `values`, the rest in
// `values_hi`; the including shader binds all four, and its RasterParams block is named
// `params`. Without PAGED there is one page of each, read as it is.

#ifdef PAGED
fn projected_at(i: u32) -> ProjectedGaussian {
    if i < params.page {
        return projected[i];
    }
    return projected_hi[i - params.page];
}

fn value_at(i: u32) -> u32 {
    if i < params.key_page {
        return values[i];
    }
    return values_hi[i - params.key_page];
}
#else
fn projected_at(i: u32) -> ProjectedGaussian {
    return projected[i];
}

fn value_at(i: u32) -> u32 {
    return values[i];
}
#endif
