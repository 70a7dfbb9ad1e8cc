// A view's projected Gaussians in pages of one binding each (toolkit::paged): the first
// `params.page` records in `projected`, the rest in `projected_hi`. The including shader binds
// both and names its RasterParams block `params`.

fn projected_at(i: u32) -> ProjectedGaussian {
    if i < params.page {
        return projected[i];
    }
    return projected_hi[i - params.page];
}
