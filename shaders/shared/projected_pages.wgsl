// A view's projected Gaussians in pages of one binding each (toolkit::paged). With PAGED (the
// kernels' variant for scenes of two pages) the first `params.page` records are in `projected`,
// the rest in `projected_hi`, which the including shader then binds; its RasterParams block is
// named `params`. Without it there is one page, read as it is.

#ifdef PAGED
fn projected_at(i: u32) -> ProjectedGaussian {
    if i < params.page {
        return projected[i];
    }
    return projected_hi[i - params.page];
}
#else
fn projected_at(i: u32) -> ProjectedGaussian {
    return projected[i];
}
#endif
