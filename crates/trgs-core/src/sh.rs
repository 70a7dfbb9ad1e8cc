//! Real spherical harmonics up to degree 3 with the constants and sign conventions of the INRIA
//! 3DGS code, so that models trained elsewhere keep their colours. Colour = sum_k basis_k(d) c_k
//! + 0.5, clamped at zero, with `d` the unit direction from the camera centre to the Gaussian.

pub const C0: f64 = 0.282_094_791_773_878_14;
pub const C1: f64 = 0.488_602_511_902_919_9;
pub const C2: [f64; 5] = [
    1.092_548_430_592_079_2,
    -1.092_548_430_592_079_2,
    0.315_391_565_252_520_05,
    -1.092_548_430_592_079_2,
    0.546_274_215_296_039_6,
];
pub const C3: [f64; 7] = [
    -0.590_043_589_926_643_5,
    2.890_611_442_640_554,
    -0.457_045_799_464_465_8,
    0.373_176_332_590_115_4,
    -0.457_045_799_464_465_8,
    1.445_305_721_320_277,
    -0.590_043_589_926_643_5,
];

/// The basis functions of degree `<= degree` at unit direction `d` (unused entries are zero).
pub fn basis(degree: u32, d: [f64; 3]) -> [f64; 16] {
    let [x, y, z] = d;
    let mut b = [0.0; 16];
    b[0] = C0;
    if degree >= 1 {
        b[1] = -C1 * y;
        b[2] = C1 * z;
        b[3] = -C1 * x;
    }
    if degree >= 2 {
        let (xx, yy, zz) = (x * x, y * y, z * z);
        b[4] = C2[0] * x * y;
        b[5] = C2[1] * y * z;
        b[6] = C2[2] * (2.0 * zz - xx - yy);
        b[7] = C2[3] * x * z;
        b[8] = C2[4] * (xx - yy);
        if degree >= 3 {
            b[9] = C3[0] * y * (3.0 * xx - yy);
            b[10] = C3[1] * x * y * z;
            b[11] = C3[2] * y * (4.0 * zz - xx - yy);
            b[12] = C3[3] * z * (2.0 * zz - 3.0 * xx - 3.0 * yy);
            b[13] = C3[4] * x * (4.0 * zz - xx - yy);
            b[14] = C3[5] * z * (xx - yy);
            b[15] = C3[6] * x * (xx - 3.0 * yy);
        }
    }
    b
}

/// Derivatives of each basis function with respect to (x, y, z) of the direction.
pub fn basis_grad(degree: u32, d: [f64; 3]) -> [[f64; 3]; 16] {
    let [x, y, z] = d;
    let mut g = [[0.0; 3]; 16];
    if degree >= 1 {
        g[1] = [0.0, -C1, 0.0];
        g[2] = [0.0, 0.0, C1];
        g[3] = [-C1, 0.0, 0.0];
    }
    if degree >= 2 {
        g[4] = [C2[0] * y, C2[0] * x, 0.0];
        g[5] = [0.0, C2[1] * z, C2[1] * y];
        g[6] = [-2.0 * C2[2] * x, -2.0 * C2[2] * y, 4.0 * C2[2] * z];
        g[7] = [C2[3] * z, 0.0, C2[3] * x];
        g[8] = [2.0 * C2[4] * x, -2.0 * C2[4] * y, 0.0];
        if degree >= 3 {
            let (xx, yy, zz) = (x * x, y * y, z * z);
            g[9] = [C3[0] * 6.0 * x * y, C3[0] * (3.0 * xx - 3.0 * yy), 0.0];
            g[10] = [C3[1] * y * z, C3[1] * x * z, C3[1] * x * y];
            g[11] = [-2.0 * C3[2] * x * y, C3[2] * (4.0 * zz - xx - 3.0 * yy), 8.0 * C3[2] * y * z];
            g[12] = [
                -6.0 * C3[3] * x * z,
                -6.0 * C3[3] * y * z,
                C3[3] * (6.0 * zz - 3.0 * xx - 3.0 * yy),
            ];
            g[13] = [C3[4] * (4.0 * zz - 3.0 * xx - yy), -2.0 * C3[4] * x * y, 8.0 * C3[4] * x * z];
            g[14] = [2.0 * C3[5] * x * z, -2.0 * C3[5] * y * z, C3[5] * (xx - yy)];
            g[15] = [C3[6] * (3.0 * xx - 3.0 * yy), -6.0 * C3[6] * x * y, 0.0];
        }
    }
    g
}

/// RGB of the SH coefficients `coeffs` (coefficient-major) at unit direction `d`, before the
/// clamp at zero: `sum_k basis_k c_k + 0.5`.
pub fn eval(degree: u32, coeffs: &[[f64; 3]], d: [f64; 3]) -> [f64; 3] {
    let b = basis(degree, d);
    let mut rgb = [0.5; 3];
    for (k, c) in coeffs.iter().enumerate().take(16) {
        for ch in 0..3 {
            rgb[ch] += b[k] * c[ch];
        }
    }
    rgb
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn basis_grad_matches_finite_differences() {
        let d = [0.3, -0.5, 0.81];
        let g = basis_grad(3, d);
        for axis in 0..3 {
            let (mut p, mut m) = (d, d);
            p[axis] += 1e-6;
            m[axis] -= 1e-6;
            let (bp, bm) = (basis(3, p), basis(3, m));
            for k in 0..16 {
                let fd = (bp[k] - bm[k]) / 2e-6;
                assert!(
                    (fd - g[k][axis]).abs() < 1e-8,
                    "basis {k} axis {axis}: {fd} vs {}",
                    g[k][axis]
                );
            }
        }
    }
}
