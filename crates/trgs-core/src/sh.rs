//! Spherical harmonics.
