//! Deterministic procedural textures: albedo as a function of surface coordinates in metres.
//!
//! Every pattern has soft edges (a few percent of its period) so that the 2x2 supersampled truth
//! is close to what a pixel integrates; hard-edged patterns alias at 256x192 and would put
//! view-dependent noise into the images that no Gaussian model can fit.
use glam::DVec3;

use trgs_core::rng::Rng;

/// Width of a pattern edge as a fraction of its period.
const EDGE: f64 = 0.06;

#[derive(Clone, Copy, Debug)]
pub(crate) enum Texture {
    /// One colour with a faint grain, so that even "plain" surfaces have trackable detail.
    Plain { colour: DVec3, grain: f64 },
    /// Checkerboard over all three coordinates (the third is 0 on flat surfaces).
    Checker { period: f64, a: DVec3, b: DVec3 },
    /// Stripes across the first coordinate.
    Stripes { period: f64, a: DVec3, b: DVec3 },
    /// Fractal value noise blending `a` into `b`.
    Noise { scale: f64, a: DVec3, b: DVec3 },
    /// Running-bond bricks with per-brick colour variation and mortar joints.
    Bricks { width: f64, height: f64, brick: DVec3, mortar: DVec3 },
    /// Tiles of random saturated colours with dark borders: book spines, posters.
    Panels { width: f64, height: f64 },
}

impl Texture {
    /// Albedo at surface coordinates `p` (flat surfaces pass `(a, b, 0)`); `seed` varies the
    /// noise and the panel colours between scenes.
    pub fn albedo(&self, p: DVec3, seed: u64) -> DVec3 {
        match *self {
            Texture::Plain { colour, grain } => {
                colour * (1.0 - grain + 2.0 * grain * fbm(p * 6.0, seed, 3))
            }
            Texture::Checker { period, a, b } => {
                let q = p / period;
                let (x, y, z) = (square(q.x), square(q.y), square(q.z));
                // Soft XOR of three square waves: a checkerboard with smooth edges.
                let xy = x + y - 2.0 * x * y;
                let s = xy + z - 2.0 * xy * z;
                a.lerp(b, s)
            }
            Texture::Stripes { period, a, b } => a.lerp(b, square(p.x / period)),
            Texture::Noise { scale, a, b } => {
                let s = smoothstep(0.3, 0.7, fbm(p / scale, seed, 4));
                a.lerp(b, s)
            }
            Texture::Bricks { width, height, brick, mortar } => {
                let row = (p.y / height).floor();
                // Every other row is shifted by half a brick (running bond).
                let u = p.x / width + 0.5 * row.rem_euclid(2.0);
                let col = u.floor();
                let (fu, fv) = (u - col, p.y / height - row);
                let joint_u = (fu.min(1.0 - fu) * width) / 0.012;
                let joint_v = (fv.min(1.0 - fv) * height) / 0.012;
                let inside = smoothstep(0.6, 1.4, joint_u.min(joint_v));
                let tint = 0.8 + 0.4 * hash(col as i64, row as i64, 17, seed);
                mortar.lerp(brick * tint, inside)
            }
            Texture::Panels { width, height } => {
                let (u, v) = (p.x / width, p.y / height);
                let (i, j) = (u.floor(), v.floor());
                let colour = palette(hash(i as i64, j as i64, 29, seed));
                let (fu, fv) = (u - i, v - j);
                // Dark borders around each panel, about 8 % of the panel size.
                let border = fu.min(1.0 - fu).min(fv.min(1.0 - fv));
                let inside = smoothstep(0.04, 0.08, border);
                DVec3::splat(0.06).lerp(colour, inside)
            }
        }
    }
}

/// A saturated colour for `h` in [0, 1): one of eight hues at two brightness levels.
fn palette(h: f64) -> DVec3 {
    const HUES: [[f64; 3]; 8] = [
        [0.80, 0.18, 0.15],
        [0.95, 0.65, 0.12],
        [0.20, 0.55, 0.22],
        [0.15, 0.35, 0.75],
        [0.55, 0.20, 0.60],
        [0.90, 0.85, 0.70],
        [0.10, 0.55, 0.60],
        [0.35, 0.22, 0.12],
    ];
    let k = ((h * 16.0) as usize).min(15);
    let c = DVec3::from_array(HUES[k % 8]);
    if k >= 8 { c * 0.7 } else { c }
}

/// Square wave of period 1 with soft edges: 1 near integers, 0 near half-integers.
fn square(x: f64) -> f64 {
    let tri = (2.0 * (x - x.floor()) - 1.0).abs();
    smoothstep(0.5 - EDGE, 0.5 + EDGE, tri)
}

fn smoothstep(lo: f64, hi: f64, x: f64) -> f64 {
    let t = ((x - lo) / (hi - lo)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// A value in [0, 1) for an integer lattice point: the crate's SplitMix64 seeded with a mix of the
/// coordinates, so that textures are pure functions of position and seed.
fn hash(i: i64, j: i64, k: i64, seed: u64) -> f64 {
    let key = seed
        ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (j as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ (k as u64).wrapping_mul(0x1656_67B1_9E37_79F9);
    Rng::new(key).uniform()
}

/// Trilinear value noise in [0, 1) with smoothstep-faded weights.
fn value_noise(p: DVec3, seed: u64) -> f64 {
    let base = p.floor();
    let f = p - base;
    let w = f * f * (DVec3::splat(3.0) - 2.0 * f);
    let (i, j, k) = (base.x as i64, base.y as i64, base.z as i64);
    let mut acc = 0.0;
    for c in 0..8 {
        let (dx, dy, dz) = (c & 1, (c >> 1) & 1, (c >> 2) & 1);
        let wx = if dx == 1 { w.x } else { 1.0 - w.x };
        let wy = if dy == 1 { w.y } else { 1.0 - w.y };
        let wz = if dz == 1 { w.z } else { 1.0 - w.z };
        acc += wx * wy * wz * hash(i + dx, j + dy, k + dz, seed);
    }
    acc
}

/// Fractal sum of `octaves` octaves of value noise, normalised to [0, 1).
fn fbm(p: DVec3, seed: u64, octaves: u32) -> f64 {
    let (mut sum, mut norm, mut amp, mut freq) = (0.0, 0.0, 1.0, 1.0);
    for o in 0..octaves {
        sum += amp * value_noise(p * freq, seed.wrapping_add(u64::from(o)));
        norm += amp;
        amp *= 0.5;
        freq *= 2.03;
    }
    sum / norm
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn textures_stay_in_range_and_are_deterministic() {
        let textures = [
            Texture::Plain { colour: DVec3::splat(0.8), grain: 0.1 },
            Texture::Checker { period: 0.3, a: DVec3::ZERO, b: DVec3::ONE },
            Texture::Stripes { period: 0.3, a: DVec3::ZERO, b: DVec3::ONE },
            Texture::Noise { scale: 0.4, a: DVec3::ZERO, b: DVec3::ONE },
            Texture::Bricks {
                width: 0.25,
                height: 0.08,
                brick: DVec3::splat(0.7),
                mortar: DVec3::splat(0.5),
            },
            Texture::Panels { width: 0.3, height: 0.4 },
        ];
        let mut rng = Rng::new(3);
        for tex in textures {
            for _ in 0..200 {
                let p =
                    DVec3::new(rng.range(-5.0, 5.0), rng.range(-5.0, 5.0), rng.range(-5.0, 5.0));
                let c = tex.albedo(p, 9);
                assert!(c.min_element() >= 0.0 && c.max_element() <= 1.0, "{tex:?} {c}");
                assert_eq!(c, tex.albedo(p, 9));
            }
        }
    }
}
