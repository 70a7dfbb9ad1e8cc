// Counter-based random numbers (twin: trgs_core::reference::{pcg_hash, noise_normal,
// draw_below}): the same u32 arithmetic as the CPU, so both draw the same numbers.

fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// Standard normal number of component c of item i at `seed` (Box-Muller on two 24-bit uniforms).
fn noise_normal(seed: u32, i: u32, c: u32) -> f32 {
    let h1 = pcg_hash((i * 3u + c) ^ pcg_hash(seed));
    let h2 = pcg_hash(h1);
    let u1 = f32((h1 >> 8u) + 1u) / 16777216.0;
    let u2 = f32(h2 >> 8u) / 16777216.0;
    return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
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

// Draw j's uniform integer below `total` (> 0) at `seed`: the high word of a 32-bit hash times
// `total`, so every value's probability is within 2^-32 of 1 / total. WGSL has no 64-bit
// integers, hence `mul_hi`.
fn draw_below(seed: u32, j: u32, total: u32) -> u32 {
    return mul_hi(pcg_hash(j ^ pcg_hash(seed)), total);
}
