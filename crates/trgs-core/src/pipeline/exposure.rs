//! The per-view exposure of stage `exposure`: an affine colour map `C' = A C + b`, stored as three
//! rows `[A_i0, A_i1, A_i2, b_i]` (the GPU reads them as three vec4).

/// A view's exposure, row by row.
pub type ExposureMatrix = [[f64; 4]; 3];

/// The exposure of a view that needs none: `C' = C`.
pub const EXPOSURE_IDENTITY: ExposureMatrix =
    [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]];
