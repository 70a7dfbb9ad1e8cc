//! Spherical-harmonic colours under an orthogonal map of directions: the coefficients `c'` with
//! `c'(d) = c(H d)` for every direction `d`. An orthogonal map keeps each SH band, so `c'` is an
//! exact linear function of `c`; it is found once per map by least squares over directions that
//! fix every band (more directions than coefficients), not by closed-form rotation formulas,
//! which would need a separate path for the improper (mirroring) maps that baking uses.
use crate::scene::sh_coeff_count;
use crate::sh::basis;
use glam::{DMat3, DVec3};

/// The linear map of SH coefficients (row-major, `k x k` for `k = (degree + 1)^2`) that turns a
/// colour `c` into `d -> c(h d)`.
#[derive(Clone, Debug)]
pub struct ShTransform {
    k: usize,
    matrix: Vec<f64>,
}

impl ShTransform {
    pub fn new(degree: u32, h: DMat3) -> Self {
        let k = sh_coeff_count(degree);
        let dirs = fibonacci_directions(4 * k + 8);
        // Normal equations (B^T B) X = B^T B_h, with B[s][j] = basis_j(d_s), B_h[s][j] =
        // basis_j(h d_s); B^T B is well conditioned for these many spread directions.
        let mut btb = vec![0.0; k * k];
        let mut btbh = vec![0.0; k * k];
        for d in &dirs {
            let b = basis(degree, d.to_array());
            let bh = basis(degree, (h * *d).normalize().to_array());
            for i in 0..k {
                for j in 0..k {
                    btb[i * k + j] += b[i] * b[j];
                    btbh[i * k + j] += b[i] * bh[j];
                }
            }
        }
        let x = solve(k, btb, btbh);
        // c'(d) = sum_j basis_j(d) c'_j = sum_i basis_i(h d) c_i, so c' = X c with X[j][i].
        Self { k, matrix: x }
    }

    /// `c'` for the coefficients `c` (`k` RGB triples).
    pub fn apply(&self, c: &[[f64; 3]]) -> Vec<[f64; 3]> {
        let k = self.k;
        (0..k)
            .map(|j| {
                let mut out = [0.0; 3];
                for (i, ci) in c.iter().enumerate().take(k) {
                    let w = self.matrix[j * k + i];
                    for ch in 0..3 {
                        out[ch] += w * ci[ch];
                    }
                }
                out
            })
            .collect()
    }
}

/// `n` directions spread evenly over the sphere.
fn fibonacci_directions(n: usize) -> Vec<DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let a = golden * i as f64;
            DVec3::new(r * a.cos(), r * a.sin(), z)
        })
        .collect()
}

/// `X` with `A X = B` for `k x k` row-major `A` (symmetric positive definite), `B` and `X`, by
/// Gaussian elimination with partial pivoting.
fn solve(k: usize, mut a: Vec<f64>, mut b: Vec<f64>) -> Vec<f64> {
    for col in 0..k {
        let pivot = (col..k)
            .max_by(|&r, &s| a[r * k + col].abs().total_cmp(&a[s * k + col].abs()))
            .unwrap_or(col);
        for c in 0..k {
            a.swap(col * k + c, pivot * k + c);
            b.swap(col * k + c, pivot * k + c);
        }
        let p = a[col * k + col];
        for r in 0..k {
            if r == col {
                continue;
            }
            let f = a[r * k + col] / p;
            if f == 0.0 {
                continue;
            }
            for c in 0..k {
                a[r * k + c] -= f * a[col * k + c];
                b[r * k + c] -= f * b[col * k + c];
            }
        }
    }
    let mut x = vec![0.0; k * k];
    for r in 0..k {
        let p = a[r * k + r];
        for c in 0..k {
            x[r * k + c] = b[r * k + c] / p;
        }
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plane_math::householder;
    use crate::sh::eval;

    /// A mirror (symmetric) and a turn (not symmetric: `h` and `h^T` differ, which a mirror
    /// alone would not tell apart).
    #[test]
    fn a_mapped_colour_is_the_colour_seen_along_the_mapped_direction() {
        let n = DVec3::new(0.3, -0.5, 0.8).normalize();
        let turn = DMat3::from_axis_angle(DVec3::new(0.2, 0.9, -0.4).normalize(), 0.7);
        for (h, degree) in
            [householder(n), turn].into_iter().flat_map(|h| (0..=3).map(move |d| (h, d)))
        {
            let k = sh_coeff_count(degree);
            let c: Vec<[f64; 3]> = (0..k)
                .map(|i| [0.3 - 0.07 * i as f64, 0.1 * (i % 3) as f64, -0.05 * i as f64])
                .collect();
            let t = ShTransform::new(degree, h);
            let mirrored = t.apply(&c);
            for d in fibonacci_directions(37) {
                let want = eval(degree, &c, (h * d).to_array());
                let got = eval(degree, &mirrored, d.to_array());
                for ch in 0..3 {
                    assert!((want[ch] - got[ch]).abs() < 1e-9, "degree {degree}: {want:?} {got:?}");
                }
            }
        }
    }

    #[test]
    fn the_identity_keeps_the_coefficients() {
        let c: Vec<[f64; 3]> = (0..16).map(|i| [i as f64, -(i as f64), 0.5]).collect();
        let same = ShTransform::new(3, DMat3::IDENTITY).apply(&c);
        for (a, b) in c.iter().zip(&same) {
            for ch in 0..3 {
                assert!((a[ch] - b[ch]).abs() < 1e-9);
            }
        }
    }
}
