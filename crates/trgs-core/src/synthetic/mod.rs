//! The procedural glass scene.
