//! The CPU reference renderer.
