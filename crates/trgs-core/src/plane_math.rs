//! Reflection-plane math.
