use super::*;
use crate::rng::Rng;
use flate2::read::GzDecoder;
use std::io::Read;

fn random_gaussians(n: usize, degree: u32, rng: &mut Rng) -> Gaussians<f32> {
    let mut g = Gaussians::empty(degree);
    for _ in 0..n {
        let sh: Vec<[f32; 3]> = (0..sh_coeff_count(degree))
            .map(|j| {
                let spread = if j == 0 { 2.0 } else { 0.6 };
                [0, 1, 2].map(|_| (spread * (2.0 * rng.uniform() - 1.0)) as f32)
            })
            .collect();
        let q = [0, 1, 2, 3].map(|_| rng.normal() as f32);
        g.push(
            [0, 1, 2].map(|_| (20.0 * (2.0 * rng.uniform() - 1.0)) as f32),
            q,
            [0, 1, 2].map(|_| (-6.0 + 5.0 * rng.uniform()) as f32),
            (6.0 * (2.0 * rng.uniform() - 1.0)) as f32,
            &sh,
            Population::Primary,
        );
    }
    g
}

fn unit(q: [f32; 4]) -> [f32; 4] {
    let n = q.iter().map(|v| v * v).sum::<f32>().sqrt();
    let s = if q[0] < 0.0 { -1.0 } else { 1.0 };
    q.map(|v| s * v / n)
}

#[test]
fn a_round_trip_loses_only_the_quantisation() {
    let mut rng = Rng::new(7);
    let g = random_gaussians(300, 3, &mut rng);
    let bytes = encode_spz(&g).expect("encode");
    let back = parse_spz(&bytes, Path::new("m.spz")).expect("parse");
    assert_eq!((back.len(), back.sh_degree), (300, 3));
    let sigmoid = |l: f32| 1.0 / (1.0 + (-l).exp());
    for i in 0..g.len() {
        for a in 0..3 {
            assert!((g.means[i][a] - back.means[i][a]).abs() <= 0.5 / 4096.0 + 1e-5);
            assert!((g.log_scales[i][a] - back.log_scales[i][a]).abs() <= 0.5 / 16.0 + 1e-5);
        }
        assert!(
            (sigmoid(g.opacity_logits[i]) - sigmoid(back.opacity_logits[i])).abs() <= 0.51 / 255.0
        );
        let (q, r) = (unit(g.rotations[i]), unit(back.rotations[i]));
        let dot: f32 = q.iter().zip(&r).map(|(a, b)| a * b).sum();
        // 9 bits per component: about a fifth of a degree.
        assert!(dot.abs() > 0.99999, "{q:?} {r:?}");
        let k = g.sh_coeffs();
        for j in 0..k {
            for ch in 0..3 {
                let (a, b) = (g.sh[i * k + j][ch], back.sh[i * k + j][ch]);
                let step = match j {
                    0 => 1.0 / (255.0 * 0.15),
                    1..=3 => 8.0 / 128.0,
                    _ => 16.0 / 128.0,
                };
                // Within half a step, or clamped at the byte range's ends.
                let clamped = if j == 0 { a.abs() > 3.3 } else { a.abs() > 0.99 };
                // (The byte is rounded before the bucket: half a byte more.)
                let tolerance = 0.5 * step + if j == 0 { 0.0 } else { 0.5 / 128.0 } + 1e-4;
                assert!((a - b).abs() <= tolerance || clamped, "coefficient {j}: {a} {b}");
            }
        }
    }
}

#[test]
fn the_header_and_layout_follow_the_reference() {
    let mut rng = Rng::new(2);
    let g = random_gaussians(5, 1, &mut rng);
    let mut raw = Vec::new();
    GzDecoder::new(&encode_spz(&g).expect("encode")[..]).read_to_end(&mut raw).expect("gzip");
    assert_eq!(&raw[0..4], b"NGSP");
    assert_eq!(u32::from_le_bytes([raw[4], raw[5], raw[6], raw[7]]), 3);
    assert_eq!(u32::from_le_bytes([raw[8], raw[9], raw[10], raw[11]]), 5);
    assert_eq!(&raw[12..16], &[1, 12, 0, 0]);
    // positions 9, alpha 1, colour 3, scales 3, rotation 4, SH 3 x 3 bytes per Gaussian.
    assert_eq!(raw.len(), 16 + 5 * (9 + 1 + 3 + 3 + 4 + 9));
    // The first position's x, as 24-bit fixed point with 12 fractional bits.
    let x = i32::from_le_bytes([raw[16], raw[17], raw[18], 0]) << 8 >> 8;
    assert_eq!(x, (g.means[0][0] * 4096.0).round() as i32);
    // y is stored negated (the file is y up).
    let y = i32::from_le_bytes([raw[19], raw[20], raw[21], 0]) << 8 >> 8;
    assert_eq!(y, (-g.means[0][1] * 4096.0).round() as i32);
}

#[test]
fn colours_keep_their_directions_across_the_frames() {
    // The file's colour seen along the file-frame direction of d is trgs's colour along d.
    let signs = rub_signs(3);
    let coeffs: Vec<[f64; 3]> = (0..16).map(|j| [0.1 * j as f64 - 0.7, 0.3, -0.2]).collect();
    let flipped: Vec<[f64; 3]> =
        coeffs.iter().zip(&signs).map(|(c, &s)| c.map(|v| v * f64::from(s))).collect();
    for d in [[0.48, 0.36, 0.8], [-0.6, 0.0, 0.8], [0.0, -1.0, 0.0]] {
        let ours = crate::sh::eval(3, &coeffs, d);
        let theirs = crate::sh::eval(3, &flipped, [d[0], -d[1], -d[2]]);
        for ch in 0..3 {
            assert!((ours[ch] - theirs[ch]).abs() < 1e-12);
        }
    }
}

#[test]
fn smallest_three_holds_every_largest_component() {
    for q in [
        [0.9, 0.1, -0.3, 0.2],
        [0.1, -0.9, 0.2, 0.3],
        [0.2, 0.1, 0.95, -0.1],
        [-0.1, 0.2, 0.3, -0.9],
    ] {
        let back = from_smallest_three(smallest_three(q));
        let q = unit(q);
        let dot: f32 = q.iter().zip(&back).map(|(a, b)| a * b).sum();
        assert!(dot.abs() > 0.99999, "{q:?} {back:?}");
    }
}

#[test]
fn bad_files_get_named_errors() {
    let path = Path::new("bad.spz");
    let message = |bytes: &[u8]| parse_spz(bytes, path).expect_err("refused").to_string();
    assert!(message(b"not gzip at all").contains("gzip"));
    let mut rng = Rng::new(3);
    let g = random_gaussians(4, 0, &mut rng);
    let good = encode_spz(&g).expect("encode");
    let mut raw = Vec::new();
    GzDecoder::new(&good[..]).read_to_end(&mut raw).expect("gzip");
    let regzip = |raw: &[u8]| {
        let mut gz = GzEncoder::new(Vec::new(), Compression::fast());
        gz.write_all(raw).expect("write");
        gz.finish().expect("finish")
    };
    let short = regzip(&raw[..raw.len() - 1]);
    assert!(message(&short).contains("4 Gaussians of SH degree 0 take"), "{}", message(&short));
    let mut v5 = raw.clone();
    v5[4] = 5;
    assert!(message(&regzip(&v5)).contains("SPZ version 5"));
    let mut v4 = raw.clone();
    v4.truncate(16);
    assert!(message(&v4).contains("version 4 header is 32 bytes"));
    let mut far = g.clone();
    far.means[2][1] = 3000.0;
    assert!(encode_spz(&far).expect_err("refused").contains("Gaussian 2"));
    // A hair under the limit rounds to 2^23 fixed-point units, which 24 bits would read back
    // as -2048: refused. Within half a unit of it, kept where it was.
    let mut edge = g.clone();
    edge.means[1][0] = 2048.0 - 1.0 / 8192.0; // 2^23 - 0.5 units
    assert!(encode_spz(&edge).expect_err("rounds out").contains("Gaussian 1"));
    edge.means[1][0] = 2048.0 - 1.0 / 1024.0;
    edge.means[1][1] = 2048.0; // -2048 in SPZ's frame (y flips), which 24 bits hold
    let back = parse_spz(&encode_spz(&edge).expect("fits"), path).expect("read");
    assert_eq!((back.means[1][0], back.means[1][1]), (2048.0 - 1.0 / 1024.0, 2048.0));
    assert!(message(&good[..10]).contains("bad.spz") || message(&good[..10]).contains("gzip"));
}

#[test]
fn sh_coefficients_past_the_byte_range_clamp() {
    for bucket in [8, 16] {
        for x in [2e7, f32::MAX] {
            assert_eq!(quantise_sh(x, bucket), quantise_sh(1.0, bucket), "{x}");
            assert_eq!(quantise_sh(-x, bucket), quantise_sh(-1.0, bucket), "{x}");
        }
    }
}

/// The attribute bytes of a version 3 file (after its 16-byte header), split per attribute.
fn attributes(g: &Gaussians<f32>) -> Vec<Vec<u8>> {
    let mut raw = Vec::new();
    GzDecoder::new(&encode_spz(g).expect("encode")[..]).read_to_end(&mut raw).expect("gzip");
    let (n, dim) = (g.len(), g.sh_coeffs() - 1);
    let mut at = 16;
    [9 * n, n, 3 * n, 3 * n, 4 * n, 3 * dim * n]
        .into_iter()
        .map(|len| {
            let part = raw[at..at + len].to_vec();
            at += len;
            part
        })
        .collect()
}

#[test]
fn version_4_streams_read_as_version_3_does() {
    let mut rng = Rng::new(11);
    for degree in [0, 2] {
        let g = random_gaussians(40, degree, &mut rng);
        let parts: Vec<Vec<u8>> = attributes(&g).into_iter().filter(|p| !p.is_empty()).collect();
        let frames: Vec<Vec<u8>> = parts
            .iter()
            .map(|p| {
                ruzstd::encoding::compress_to_vec(
                    &p[..],
                    ruzstd::encoding::CompressionLevel::Fastest,
                )
            })
            .collect();
        let mut file = Vec::new();
        file.extend_from_slice(&MAGIC.to_le_bytes());
        file.extend_from_slice(&4u32.to_le_bytes());
        file.extend_from_slice(&40u32.to_le_bytes());
        file.extend_from_slice(&[degree as u8, 12, 0, frames.len() as u8]);
        file.extend_from_slice(&32u32.to_le_bytes());
        file.extend_from_slice(&[0; 12]);
        for (f, p) in frames.iter().zip(&parts) {
            file.extend_from_slice(&(f.len() as u64).to_le_bytes());
            file.extend_from_slice(&(p.len() as u64).to_le_bytes());
        }
        for f in &frames {
            file.extend_from_slice(f);
        }
        let from_v4 = parse_spz(&file, Path::new("v4.spz")).expect("v4");
        let from_v3 = parse_spz(&encode_spz(&g).expect("encode"), Path::new("v3.spz")).expect("v3");
        assert_eq!(from_v4.means, from_v3.means, "degree {degree}");
        assert_eq!(from_v4.sh, from_v3.sh);
        assert_eq!(from_v4.rotations, from_v3.rotations);
        // A byte after the last stream is refused.
        file.push(0);
        let e = parse_spz(&file, Path::new("v4.spz")).expect_err("trailing byte");
        assert!(e.to_string().contains("1 bytes after the last stream"), "{e}");
    }
}

#[test]
fn a_coordinate_system_record_of_rdf_keeps_the_frame() {
    let mut rng = Rng::new(12);
    let g = random_gaussians(10, 1, &mut rng);
    let mut raw = Vec::new();
    GzDecoder::new(&encode_spz(&g).expect("encode")[..]).read_to_end(&mut raw).expect("gzip");
    let rub = parse_spz(&encode_spz(&g).expect("encode"), Path::new("a.spz")).expect("rub");
    // The same bytes said to be right-down-forward: positions come back as stored.
    raw[14] |= 0x2;
    for v in [0xADBE_0003u32, 4, 6] {
        raw.extend_from_slice(&v.to_le_bytes());
    }
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(&raw).expect("write");
    let rdf = parse_spz(&gz.finish().expect("gzip"), Path::new("b.spz")).expect("rdf");
    for (a, b) in rub.means.iter().zip(&rdf.means) {
        assert_eq!([a[0], -a[1], -a[2]], *b);
    }
}
