//! The layout of the depth-order keys ([`crate::reference::depth_key`]): how many bits they
//! take, which the GPU's radix sort needs, and the depth they count from, which the GPU gets as
//! a parameter of each view.

/// Bits of a [`depth_key`](crate::reference::depth_key): five six-bit radix passes instead of
/// six for 32 bits.
pub const DEPTH_KEY_BITS: u32 = 30;

/// The smallest depth the keys count from: a near plane closer than this (allowed, but odd) keys
/// depths from here instead, so that the 30 bits still span 2^128 from it.
pub const DEPTH_KEY_FLOOR: f32 = 5.421_011e-20; // 2^-64

/// The f32 bits of the depth base of [`depth_key`](crate::reference::depth_key) for a near plane
/// at `near`.
pub fn depth_key_base(near: f64) -> u32 {
    (near as f32).max(DEPTH_KEY_FLOOR).to_bits()
}
