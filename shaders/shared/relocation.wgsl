// What the `mcmc_relocate` kernels share (twins in trgs_train::densify::mcmc): the opacity bin of
// a logit, by which relocation weighs its draws and looks Eq. 9 up, and a draw's uniform integer.
// Both are exact (a correctly rounded subtraction, a multiplication by a power of two, integer
// arithmetic), so that the GPU and the twin draw the same Gaussians.
#include "shared/random.wgsl"

fn opacity_bin(logit: f32) -> u32 {
    let x = floor((logit - RELOCATION_BIN_LO) * RELOCATION_BINS_PER_UNIT);
    return u32(clamp(x, 0.0, f32(RELOCATION_BINS - 1u)));
}

// The high word of the 64-bit product a * b, from 16-bit halves.
fn mul_hi(a: u32, b: u32) -> u32 {
    let a0 = a & 0xffffu;
    let a1 = a >> 16u;
    let b0 = b & 0xffffu;
    let b1 = b >> 16u;
    let lo = a0 * b0;
    let mid1 = a1 * b0;
    let mid2 = a0 * b1;
    let carry = ((lo >> 16u) + (mid1 & 0xffffu) + (mid2 & 0xffffu)) >> 16u;
    return a1 * b1 + (mid1 >> 16u) + (mid2 >> 16u) + carry;
}

// Draw j's uniform integer below `total`.
fn draw_below(seed: u32, j: u32, total: u32) -> u32 {
    return mul_hi(pcg_hash(j ^ pcg_hash(seed)), total);
}
