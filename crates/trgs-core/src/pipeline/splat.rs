//! How a Gaussian becomes a splat and how splats blend: the thresholds that `project`, both
//! rasterize passes and their adjoints apply, on the GPU and in the twins alike.

/// Added to the diagonal of every 2D covariance (px^2): EWA's low-pass filter as in 3DGS.
pub const COV2D_BLUR: f64 = 0.3;
/// Upper bound on a Gaussian's alpha; keeps `1 - alpha` away from zero for the backward replay.
pub const MAX_ALPHA: f64 = 0.99;
/// Contributions with alpha below this are skipped (they cannot change an 8-bit pixel).
pub const MIN_ALPHA: f64 = 1.0 / 255.0;
/// A Gaussian that would bring a transmittance below this is not blended, and that chain stops.
pub const MIN_TRANSMITTANCE: f64 = 1e-4;
/// The Jacobian of the projection is evaluated with the mean clamped to this guard band around
/// the image (as a fraction of its size on each side): 3DGS's 1.3 x tan(fov / 2).
pub const GUARD_BAND: f64 = 0.15;
