// What the `mcmc_relocate` kernels share (twins in trgs_train::densify::mcmc): the opacity bin of
// a logit, by which relocation weighs its draws and looks Eq. 9 up. It is exact (a correctly
// rounded subtraction, a multiplication by a power of two), and so are the draws' uniform
// integers (`draw_below`, shared/random.wgsl), so that the GPU and the twin draw the same
// Gaussians.
#include "shared/random.wgsl"

fn opacity_bin(logit: f32) -> u32 {
    let x = floor((logit - RELOCATION_BIN_LO) * RELOCATION_BINS_PER_UNIT);
    return u32(clamp(x, 0.0, f32(RELOCATION_BINS - 1u)));
}
