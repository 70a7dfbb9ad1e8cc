//! The weights of the training losses: the D-SSIM share of the photometric loss and the
//! regularisers' weights, which the GPU loss stages and their twins (`photometric_loss`,
//! `regularisers`) take alike.

/// 3DGS's weight of the D-SSIM term.
pub const DSSIM_LAMBDA: f64 = 0.2;

/// The weights of the three regularisers (zero switches one off).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RegulariserWeights {
    pub depth: f64,
    pub conflict: f64,
    pub mask: f64,
}
