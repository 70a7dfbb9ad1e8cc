//! Niantic's SPZ, the compressed splat format that Scaniverse writes and SuperSplat, Spark and
//! others read: a gzip stream of a 16-byte header and then, for all Gaussians at once, each
//! attribute quantised to bytes (positions as 24-bit fixed point, the rest as 8 bits).
//!
//! Written by hand after the reference implementation's format (nianticlabs/spz, `load-spz.cc`):
//! the crates.io ports (`spz` 0.0.6, `spz-rs` 0.1.0) are young single-author ones, and the
//! format is a few pages.
//! trgs writes version 3 (gzip, rotations as "smallest three"), which every reader of the
//! format reads (the reference's newest writer defaults to version 4, one zstd frame per
//! attribute, which older readers refuse); it reads versions 2, 3 and 4 (`container`; zstd by
//! ruzstd, a pure-Rust decoder).
//!
//! The file holds its Gaussians in a right-up-back frame (x right, y up, z back, as OpenGL and
//! glTF); trgs's, like the INRIA PLY's, is COLMAP's right-down-forward. The two differ by a half
//! turn about x: positions and quaternion axes flip y and z, and each SH coefficient flips sign
//! with its basis function (`rub_sign`), as the reference converts from a PLY.
//!
//! What is lost: positions to 1/4096 of a unit, colours and opacities to 8 bits, log-scales to
//! 1/16, degree-1 SH to 5 bits and higher degrees to 4 bits, rotations to 9 bits per component;
//! trgs's own fields (planes, glass Gaussians' masks, reflection intensities) are not stored.
use super::{FormatError, write_atomic};
use crate::reference::sigmoid;
use crate::scene::{Gaussians, Population, sh_coeff_count};
use container::{MAGIC, Packed, StoredFrame};
use flate2::Compression;
use flate2::write::GzEncoder;
use std::io::Write;
use std::path::Path;

mod container;

/// The version written: gzip, smallest-three rotations.
const VERSION: u32 = 3;
/// Bits after the binary point of the 24-bit positions (the reference's choice: 0.25 mm in
/// metres).
const FRACTIONAL_BITS: u8 = 12;
/// The DC colour's scale: byte = 255 (0.15 dc + 0.5).
const COLOUR_SCALE: f32 = 0.15;
/// SH quantisation: buckets of 2^(8 - bits) byte values, for degree 1 and for higher degrees.
const SH1_BITS: u32 = 5;
const SH_REST_BITS: u32 = 4;

/// The Gaussians in SPZ, gzip-compressed (glass Gaussians are written as any other). A
/// position beyond what 24 bits hold (2048 units from the origin) is refused, naming it.
pub fn encode_spz(g: &Gaussians<f32>) -> Result<Vec<u8>, String> {
    let n = g.len();
    let unit = f32::from(1u16 << FRACTIONAL_BITS);
    let limit = (1 << 23) as f32 / unit;
    // Checked on the rounded fixed-point value: a position a hair under +limit rounds to
    // 2^23, which 24 bits read back as -2^23.
    let fits = |v: f32| {
        let fixed = (v * unit).round();
        fixed >= -((1 << 23) as f32) && fixed < (1 << 23) as f32
    };
    if let Some(i) = g.means.iter().position(|&m| !rub_position(m).into_iter().all(fits)) {
        return Err(format!(
            "Gaussian {i} at {:?}: SPZ holds positions within {limit} units of the origin",
            g.means[i]
        ));
    }
    let k = g.sh_coeffs();
    let signs = rub_signs(g.sh_degree);
    let mut raw = Vec::with_capacity(16 + n * (9 + 1 + 3 + 3 + 4 + 3 * (k - 1)));
    raw.extend_from_slice(&MAGIC.to_le_bytes());
    raw.extend_from_slice(&VERSION.to_le_bytes());
    raw.extend_from_slice(&(n as u32).to_le_bytes());
    raw.extend_from_slice(&[g.sh_degree as u8, FRACTIONAL_BITS, 0, 0]);
    for m in &g.means {
        for v in rub_position(*m) {
            let fixed = (v * unit).round() as i32;
            raw.extend_from_slice(&fixed.to_le_bytes()[..3]);
        }
    }
    raw.extend(g.opacity_logits.iter().map(|&l| to_u8(sigmoid(f64::from(l)) as f32 * 255.0)));
    for i in 0..n {
        raw.extend(g.sh[i * k].map(|dc| to_u8(dc * COLOUR_SCALE * 255.0 + 127.5)));
    }
    for s in &g.log_scales {
        raw.extend(s.map(|v| to_u8((v + 10.0) * 16.0)));
    }
    for q in &g.rotations {
        raw.extend_from_slice(&smallest_three(rub_quaternion(*q)).to_le_bytes());
    }
    for i in 0..n {
        for j in 1..k {
            for ch in 0..3 {
                let bits = if j < 4 { SH1_BITS } else { SH_REST_BITS };
                raw.push(quantise_sh(g.sh[i * k + j][ch] * signs[j], 1 << (8 - bits)));
            }
        }
    }
    let mut gz = GzEncoder::new(Vec::new(), Compression::default());
    // Writing to a Vec cannot fail.
    gz.write_all(&raw).map_err(|e| e.to_string())?;
    gz.finish().map_err(|e| e.to_string())
}

/// Write `g` as an SPZ file (whole or not at all).
pub fn write_spz(path: &Path, g: &Gaussians<f32>) -> Result<(), FormatError> {
    let bytes = encode_spz(g).map_err(|e| FormatError::new(path, e))?;
    write_atomic(path, &bytes)
}

/// Read an SPZ file of version 2, 3 or 4 into primary Gaussians.
pub fn read_spz(path: &Path) -> Result<Gaussians<f32>, FormatError> {
    let bytes = std::fs::read(path).map_err(|e| FormatError::io(path, &e))?;
    parse_spz(&bytes, path)
}

/// Parse the bytes of an SPZ file; `path` names it in errors.
pub fn parse_spz(bytes: &[u8], path: &Path) -> Result<Gaussians<f32>, FormatError> {
    let packed = container::open(bytes).map_err(|e| FormatError::new(path, e))?;
    Ok(unpack(&packed))
}

/// The Gaussians of an opened file, in trgs's frame.
fn unpack(p: &Packed) -> Gaussians<f32> {
    let (n, degree) = (p.count, p.sh_degree);
    let k = sh_coeff_count(degree);
    let rub = p.frame == StoredFrame::Rub;
    let signs = if rub { rub_signs(degree) } else { vec![1.0; k] };
    let position = |m: [f32; 3]| if rub { rub_position(m) } else { m };
    let rotation = |q: [f32; 4]| if rub { rub_quaternion(q) } else { q };
    let unit = 1.0 / f32::from(1u16 << p.fractional_bits.min(15));
    let mut g = Gaussians::empty(degree);
    let mut coeffs = vec![[0.0f32; 3]; k];
    for i in 0..n {
        let b = &p.positions[9 * i..9 * i + 9];
        // Each coordinate is 24-bit two's complement: sign-extended through the top byte.
        let coord = |a: usize| {
            (i32::from_le_bytes([b[3 * a], b[3 * a + 1], b[3 * a + 2], 0]) << 8 >> 8) as f32 * unit
        };
        let q = if p.version >= 3 {
            let r = &p.rotations[4 * i..4 * i + 4];
            from_smallest_three(u32::from_le_bytes([r[0], r[1], r[2], r[3]]))
        } else {
            from_first_three(&p.rotations[3 * i..3 * i + 3])
        };
        coeffs[0] =
            [0, 1, 2].map(|ch| (f32::from(p.colours[3 * i + ch]) / 255.0 - 0.5) / COLOUR_SCALE);
        for (j, c) in coeffs.iter_mut().enumerate().skip(1) {
            let at = 3 * ((k - 1) * i + j - 1);
            *c = [0, 1, 2].map(|ch| (f32::from(p.sh[at + ch]) - 128.0) / 128.0 * signs[j]);
        }
        g.push(
            position([coord(0), coord(1), coord(2)]),
            rotation(q),
            [0, 1, 2].map(|a| f32::from(p.scales[3 * i + a]) / 16.0 - 10.0),
            logit(f32::from(p.alphas[i]) / 255.0),
            &coeffs,
            Population::Primary,
        );
    }
    g
}

/// A point between trgs's frame and the file's (the same half turn both ways).
fn rub_position(p: [f32; 3]) -> [f32; 3] {
    [p[0], -p[1], -p[2]]
}

/// A rotation (w x y z) between the frames: conjugated by the half turn about x, its axis flips
/// in y and z.
fn rub_quaternion(q: [f32; 4]) -> [f32; 4] {
    [q[0], q[1], -q[2], -q[3]]
}

/// For each SH coefficient, the sign its basis function takes under the half turn about x
/// (y and z negated): +1 or -1, from the basis itself at a direction with no zero component.
fn rub_signs(degree: u32) -> Vec<f32> {
    let d = [0.48, 0.36, 0.8];
    let (b, f) = (crate::sh::basis(degree, d), crate::sh::basis(degree, [d[0], -d[1], -d[2]]));
    (0..sh_coeff_count(degree)).map(|j| if b[j] * f[j] < 0.0 { -1.0 } else { 1.0 }).collect()
}

/// A unit quaternion (w x y z) as the reference's "smallest three": the index of the largest
/// component (of x y z w) in the top two bits, the other three in order, each as a sign bit and
/// 9 bits of magnitude in units of sqrt(1/2) / 511, the first in the highest bits; the largest
/// is made positive (q and -q are one rotation) and recovered from the unit length.
fn smallest_three(q: [f32; 4]) -> u32 {
    let [w, x, y, z] = q;
    let norm = (w * w + x * x + y * y + z * z).sqrt().max(f32::MIN_POSITIVE);
    let xyzw = [x / norm, y / norm, z / norm, w / norm];
    let largest = (0..4).fold(0, |l, i| if xyzw[i].abs() > xyzw[l].abs() { i } else { l });
    let negate = xyzw[largest] < 0.0;
    let mut packed = largest as u32;
    for (i, &c) in xyzw.iter().enumerate() {
        if i == largest {
            continue;
        }
        let sign = u32::from((c < 0.0) != negate);
        let magnitude = (511.0 * (c.abs() / std::f32::consts::FRAC_1_SQRT_2) + 0.5) as u32;
        packed = (packed << 10) | (sign << 9) | magnitude.min(511);
    }
    packed
}

/// The unit quaternion (w x y z) of [`smallest_three`].
fn from_smallest_three(mut packed: u32) -> [f32; 4] {
    let largest = (packed >> 30) as usize;
    let mut xyzw = [0.0f32; 4];
    let mut sum = 0.0;
    for i in (0..4).rev() {
        if i == largest {
            continue;
        }
        let magnitude = (packed & 511) as f32 / 511.0 * std::f32::consts::FRAC_1_SQRT_2;
        let negative = packed & 512 != 0;
        packed >>= 10;
        xyzw[i] = if negative { -magnitude } else { magnitude };
        sum += magnitude * magnitude;
    }
    xyzw[largest] = (1.0 - sum).max(0.0).sqrt();
    [xyzw[3], xyzw[0], xyzw[1], xyzw[2]]
}

/// Version 2's rotation: x y z as signed bytes (w made positive and recovered).
fn from_first_three(b: &[u8]) -> [f32; 4] {
    let [x, y, z] = [0, 1, 2].map(|i| f32::from(b[i]) / 127.5 - 1.0);
    [(1.0 - x * x - y * y - z * z).max(0.0).sqrt(), x, y, z]
}

/// The reference's SH quantisation: 8 bits (x in [-1, 1]), rounded to the centre of a bucket.
fn quantise_sh(x: f32, bucket: i32) -> u8 {
    // Clamped before the integer cast: a coefficient past 1.7e7 would overflow the sum.
    let q = ((x * 128.0).round() + 128.0).clamp(0.0, 255.0) as i32;
    let q = (q + bucket / 2) / bucket * bucket;
    q.clamp(0, 255) as u8
}

fn to_u8(x: f32) -> u8 {
    x.round().clamp(0.0, 255.0) as u8
}

/// The logit of a byte opacity, finite at 0 and 1.
fn logit(a: f32) -> f32 {
    let a = a.clamp(0.5 / 255.0, 1.0 - 0.5 / 255.0);
    (a / (1.0 - a)).ln()
}

#[cfg(test)]
mod tests;
