// Counter-based random numbers (twin: trgs_core::reference::{pcg_hash, noise_normal}): the same
// u32 arithmetic as the CPU, so both draw the same numbers.

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
