use std::path::Path;

use super::*;
use crate::io::test_util::{assert_mentions, scratch_dir};

const P: &str = "test.ply";

/// A small deterministic generator of arbitrary finite f32 bit patterns (subnormals, -0, huge).
fn values(seed: u64) -> impl FnMut() -> f32 {
    let mut s = seed;
    move || loop {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let v = f32::from_bits((s >> 32) as u32);
        if v.is_finite() {
            return v;
        }
    }
}

/// Gaussians of arbitrary values a model file can hold: log-scales and log reflections whose exp
/// is finite (negated when it is not), rotations whose squared length is finite.
fn sample(n: usize, degree: u32) -> Gaussians<f32> {
    let mut v = values(u64::from(degree) + 70);
    let mut log = move || {
        let l = v();
        if l.exp().is_finite() { l } else { -l.abs() }
    };
    let mut v = values(u64::from(degree) + 7);
    let mut g = Gaussians::zeros(n, degree);
    for i in 0..n {
        g.means[i] = [v(), v(), v()];
        g.rotations[i] = [v(), v(), v(), v()].map(|r| r.clamp(-1e18, 1e18));
        g.log_scales[i] = [log(), log(), log()];
        g.opacity_logits[i] = v();
        g.mask_logits[i] = v();
        g.log_reflections[i] = log();
        g.populations[i] = if i % 3 == 1 { Population::Glass } else { Population::Primary };
    }
    g.sh.iter_mut().for_each(|c| *c = [v(), v(), v()]);
    g.means[0] = [-0.0, f32::MIN_POSITIVE / 4.0, f32::MAX];
    g
}

/// Every stored value as bits, so that -0.0 and 0.0 differ and the comparison is exact.
fn bits(g: &Gaussians<f32>) -> Vec<u32> {
    let mut out = vec![g.sh_degree, g.len() as u32];
    out.extend(g.means.iter().flatten().map(|v| v.to_bits()));
    out.extend(g.rotations.iter().flatten().map(|v| v.to_bits()));
    out.extend(g.log_scales.iter().flatten().map(|v| v.to_bits()));
    out.extend(g.opacity_logits.iter().map(|v| v.to_bits()));
    out.extend(g.sh.iter().flatten().map(|v| v.to_bits()));
    out.extend(g.mask_logits.iter().map(|v| v.to_bits()));
    out.extend(g.log_reflections.iter().map(|v| v.to_bits()));
    out.extend(g.populations.iter().map(|&p| p as u32));
    out
}

#[test]
fn round_trip_is_bit_exact_at_every_degree() {
    for degree in 0..=3 {
        let g = sample(5, degree);
        let back = parse_ply(&encode_ply(&g).expect("encode"), Path::new(P)).expect("parse");
        assert_eq!(bits(&back), bits(&g), "degree {degree}");
    }
    let dir = scratch_dir("ply-file");
    let g = sample(3, 2);
    write_ply(&dir.join("m.ply"), &g).expect("write");
    assert_eq!(bits(&read_ply(&dir.join("m.ply")).expect("read")), bits(&g));
    let empty = Gaussians::empty(3);
    let back = parse_ply(&encode_ply(&empty).expect("encode"), Path::new(P)).expect("parse");
    assert!(back.is_empty() && back.sh_degree == 3, "the header alone keeps the degree");
}

#[test]
fn writer_uses_inria_header_and_channel_major_rest() {
    let mut g = Gaussians::<f32>::zeros(1, 1);
    // Coefficient j of channel c = 10 j + c.
    for j in 0..4 {
        g.sh[j] = [10.0 * j as f32, 10.0 * j as f32 + 1.0, 10.0 * j as f32 + 2.0];
    }
    // A glass Gaussian: trgs's extras are written.
    g.populations[0] = Population::Glass;
    let bytes = encode_ply(&g).expect("encode");
    let names = [
        "x",
        "y",
        "z",
        "nx",
        "ny",
        "nz",
        "f_dc_0",
        "f_dc_1",
        "f_dc_2",
        "f_rest_0",
        "f_rest_1",
        "f_rest_2",
        "f_rest_3",
        "f_rest_4",
        "f_rest_5",
        "f_rest_6",
        "f_rest_7",
        "f_rest_8",
        "opacity",
        "scale_0",
        "scale_1",
        "scale_2",
        "rot_0",
        "rot_1",
        "rot_2",
        "rot_3",
        "trgs_mask",
        "trgs_reflection",
        "trgs_population",
    ];
    let mut header = String::from("ply\nformat binary_little_endian 1.0\nelement vertex 1\n");
    names.iter().for_each(|n| header.push_str(&format!("property float {n}\n")));
    header.push_str("end_header\n");
    assert!(bytes.starts_with(header.as_bytes()));
    let floats: Vec<f32> = bytes[header.len()..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    assert_eq!(
        &floats[6..18],
        [0.0, 1.0, 2.0, 10.0, 20.0, 30.0, 11.0, 21.0, 31.0, 12.0, 22.0, 32.0]
    );
}

#[test]
fn a_model_without_glass_is_written_as_inria_rows() {
    // SIBR reads 62 floats a Gaussian at degree 3, whatever the header says.
    let g = plain(4, 3);
    let bytes = encode_ply(&g).expect("encode");
    let body = bytes.windows(11).position(|w| w == b"end_header\n").expect("header") + 11;
    assert_eq!(bytes.len() - body, 4 * 62 * 4);
    assert!(!bytes.windows(5).any(|w| w == b"trgs_"), "no extras");
    let back = parse_ply(&bytes, Path::new("plain.ply")).expect("read");
    assert_eq!(bits(&back), bits(&g));
}

/// A binary little-endian file from a header and one value per (vertex, property), as another
/// tool would write it; returns the bytes and the value function.
fn emulate(comments: &[&str], names: &[String], n: usize) -> Vec<u8> {
    let mut header = String::from("ply\nformat binary_little_endian 1.0\n");
    comments.iter().for_each(|c| header.push_str(&format!("comment {c}\n")));
    header.push_str(&format!("element vertex {n}\n"));
    names.iter().for_each(|p| header.push_str(&format!("property float {p}\n")));
    header.push_str("end_header\n");
    let mut bytes = header.into_bytes();
    for i in 0..n {
        for p in 0..names.len() {
            bytes.extend(value(i, p).to_le_bytes());
        }
    }
    bytes
}

/// Distinct for every vertex and property, exact in f32, and small enough for a log-scale.
fn value(i: usize, p: usize) -> f32 {
    (i * 1000 + p) as f32 / 128.0 + 0.25
}

/// Check every attribute of `g` against the emulated file, looking each value up by name.
fn check_emulated(g: &Gaussians<f32>, names: &[String], n: usize, degree: u32) {
    let at = |i: usize, name: &str| value(i, names.iter().position(|p| p == name).expect(name));
    assert_eq!((g.len(), g.sh_degree), (n, degree));
    let k = sh_coeff_count(degree);
    for i in 0..n {
        assert_eq!(g.means[i], [at(i, "x"), at(i, "y"), at(i, "z")]);
        assert_eq!(g.log_scales[i], [at(i, "scale_0"), at(i, "scale_1"), at(i, "scale_2")]);
        assert_eq!(
            g.rotations[i],
            [at(i, "rot_0"), at(i, "rot_1"), at(i, "rot_2"), at(i, "rot_3")]
        );
        assert_eq!(g.opacity_logits[i], at(i, "opacity"));
        assert_eq!(g.sh_of(i)[0], [at(i, "f_dc_0"), at(i, "f_dc_1"), at(i, "f_dc_2")]);
        for j in 1..k {
            for c in 0..3 {
                assert_eq!(g.sh_of(i)[j][c], at(i, &format!("f_rest_{}", c * (k - 1) + j - 1)));
            }
        }
        assert_eq!(
            (g.mask_logits[i], g.log_reflections[i], g.populations[i]),
            (0.0, 0.0, Population::Primary)
        );
    }
}

fn names(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

fn rest(count: usize) -> Vec<String> {
    (0..count).map(|k| format!("f_rest_{k}")).collect()
}

#[test]
fn reads_inria_layout_with_normals_at_degree_3() {
    let mut props = names(&["x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"]);
    props.extend(rest(45));
    props.extend(names(&[
        "opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3",
    ]));
    let g = parse_ply(&emulate(&[], &props, 3), Path::new(P)).expect("INRIA file");
    check_emulated(&g, &props, 3, 3);
    // Spelled out once: coefficient 1 of green is f_rest_15, the 25th property.
    assert_eq!(g.sh_of(2)[1][1], value(2, 9 + 15));
}

#[test]
fn reads_gsplat_export_without_normals() {
    // gsplat's `splat2ply_bytes`: means, sh0, shN (channel-major), opacity, scales, quats.
    let mut props = names(&["x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2"]);
    props.extend(rest(24));
    props.extend(names(&[
        "opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3",
    ]));
    let g = parse_ply(&emulate(&[], &props, 4), Path::new(P)).expect("gsplat file");
    check_emulated(&g, &props, 4, 2);
}

#[test]
fn reads_brush_export_order_and_comments() {
    // Brush (its brush-serde exporter): comments, then x y z, scales, opacity, rotation, f_dc, f_rest.
    let comments =
        ["Exported from Brush", "Vertical axis: y", "SH degree: 1", "SplatRenderMode: default"];
    let mut props = names(&["x", "y", "z", "scale_0", "scale_1", "scale_2", "opacity"]);
    props.extend(names(&["rot_0", "rot_1", "rot_2", "rot_3", "f_dc_0", "f_dc_1", "f_dc_2"]));
    props.extend(rest(9));
    let g = parse_ply(&emulate(&comments, &props, 2), Path::new(P)).expect("Brush file");
    check_emulated(&g, &props, 2, 1);
}

const MIN_PROPS: &str = "property float x\nproperty float y\nproperty float z\nproperty float f_dc_0\n\
    property float f_dc_1\nproperty float f_dc_2\nproperty float opacity\nproperty float scale_0\n\
    property float scale_1\nproperty float scale_2\nproperty float rot_0\nproperty float rot_1\n\
    property float rot_2\nproperty float rot_3\n";

#[test]
fn reads_ascii_with_other_elements_and_types() {
    let text = "ply\nformat ascii 1.0\ncomment hand written\nelement face 2\n\
        property list uchar int vertex_indices\nproperty uint8 flags\nelement vertex 2\n\
        property double x\nproperty float32 y\nproperty short z\nproperty uchar red\n\
        property float f_dc_0\nproperty float f_dc_1\nproperty float f_dc_2\nproperty float opacity\n\
        property float scale_0\nproperty float scale_1\nproperty float scale_2\nproperty float rot_0\n\
        property float rot_1\nproperty float rot_2\nproperty float rot_3\nproperty uchar trgs_population\n\
        property list uint8 float junk\nelement camera 1\nproperty float fov\nend_header\n\
        3 0 1 2 7\n0 9\n\
        0.1 2.5 -3 255 1 2 3 0.5 -1 -2 -3 1 0 0 0 1 2 1.5 2.5\n\
        4 5 6 0 7 8 9 1.5 -4 -5 -6 0 1 0 0 0 0\n\
        60\n";
    let g = parse_ply(text.as_bytes(), Path::new(P)).expect("ascii");
    assert_eq!(g.means, [[0.1f64 as f32, 2.5, -3.0], [4.0, 5.0, 6.0]]);
    assert_eq!(g.populations, [Population::Glass, Population::Primary]);
    assert_eq!(g.rotations[1], [0.0, 1.0, 0.0, 0.0]);
    assert_eq!(g.sh_degree, 0);
}

#[test]
fn reads_big_endian_with_list_element_before_vertex() {
    let header = format!(
        "ply\r\nformat binary_big_endian 1.0\r\nelement face 2\r\nproperty list uchar int idx\r\n\
         element vertex 1\r\n{}property double trgs_reflection\r\nend_header\n",
        MIN_PROPS.replace('\n', "\r\n")
    );
    let mut bytes = header.into_bytes();
    bytes.extend([2, 0, 0, 0, 1, 0, 0, 0, 2, 0]); // faces: [1, 2] and []
    for k in 0..14 {
        bytes.extend((k as f32).to_be_bytes());
    }
    bytes.extend(0.75f64.to_be_bytes());
    let g = parse_ply(&bytes, Path::new(P)).expect("big endian");
    assert_eq!(g.means[0], [0.0, 1.0, 2.0]);
    assert_eq!(g.rotations[0], [10.0, 11.0, 12.0, 13.0]);
    assert_eq!(g.log_reflections[0], 0.75);
}

/// `n` plain Gaussians at SH degree `degree`: unit rotations, small scales, every value usable.
fn plain(n: usize, degree: u32) -> Gaussians<f32> {
    let mut g = Gaussians::<f32>::zeros(n, degree);
    for i in 0..n {
        g.means[i] = [i as f32, 0.5, 2.0];
        g.rotations[i] = [1.0, 0.0, 0.0, 0.0];
        g.log_scales[i] = [-2.0, -3.0, -4.0];
        g.opacity_logits[i] = 0.5;
    }
    g
}

/// `bytes` with the 4 bytes of property `name` of vertex `i` (a file `encode_ply` wrote at
/// `degree`) replaced by `v`.
fn with_value(bytes: &[u8], degree: u32, i: usize, name: &str, v: f32) -> Vec<u8> {
    let extras = bytes.windows(9).any(|w| w == b"trgs_mask");
    let names = property_names(degree, extras);
    let body = bytes.windows(11).position(|w| w == b"end_header\n").expect("header") + 11;
    let p = names.iter().position(|n| n == name).expect(name);
    let at = body + (i * names.len() + p) * 4;
    let mut out = bytes.to_vec();
    out[at..at + 4].copy_from_slice(&v.to_le_bytes());
    out
}

#[test]
fn values_that_cannot_be_used_finitely_are_refused_at_the_read() {
    let dir = scratch_dir("ply-finite");
    let path = dir.join("huge.ply");
    let mut model = plain(20, 1);
    model.populations[3] = Population::Glass;
    let good = encode_ply(&model).expect("encode");
    let cases: [(&str, f32, &[&str]); 5] = [
        ("scale_0", 1e30, &["Gaussian 17", "scale_0 = 1e30", "log-scale", "exp"]),
        ("scale_2", 89.0, &["Gaussian 17", "scale_2 = 89.0", "log-scale"]),
        ("opacity", f32::NAN, &["Gaussian 17", "opacity = NaN", "not finite"]),
        ("f_rest_4", f32::INFINITY, &["Gaussian 17", "f_rest_4 = inf"]),
        ("trgs_reflection", 100.0, &["Gaussian 17", "trgs_reflection = 100.0", "exp"]),
    ];
    for (name, v, parts) in cases {
        let bytes = with_value(&good, 1, 17, name, v);
        std::fs::write(&path, &bytes).expect("write");
        assert_mentions(&read_ply(&path).expect_err(name), &[&["huge.ply"], parts].concat());
        assert_mentions(&parse_ply(&bytes, &path).expect_err(name), parts);
    }
    // The largest log-scale whose exp is finite reads.
    let bytes = with_value(&good, 1, 17, "scale_1", 88.0);
    assert_eq!(parse_ply(&bytes, &path).expect("e^88").log_scales[17][1], 88.0);
}

#[test]
fn the_writers_refuse_what_the_readers_would_refuse() {
    let dir = scratch_dir("ply-write-finite");
    let mut g = plain(3, 0);
    g.log_scales[1][2] = 100.0;
    let err = write_ply(&dir.join("w.ply"), &g).expect_err("huge log-scale");
    assert_mentions(&err, &["w.ply", "Gaussian 1", "scale_2 = 100.0"]);
    let err = crate::io::write_glb(&dir.join("w.glb"), &g, &[]).expect_err("huge log-scale");
    assert_mentions(&err, &["w.glb", "Gaussian 1", "SCALE", "100.0"]);
    let mut g = plain(3, 0);
    g.means[2][1] = f32::NAN;
    assert_mentions(&encode_ply(&g).expect_err("NaN"), &["Gaussian 2", "y = NaN"]);
    let err = crate::io::encode_glb(&g, &[]).expect_err("NaN");
    assert_mentions(&err, &["Gaussian 2", "POSITION", "NaN"]);
}

#[test]
fn data_after_the_declared_elements_is_refused() {
    let dir = scratch_dir("ply-after");
    let path = dir.join("short.ply");
    // Binary: three Gaussians written, two declared.
    let three = encode_ply(&plain(3, 0)).expect("encode");
    let header_end = three.windows(11).position(|w| w == b"end_header\n").expect("header");
    let header = String::from_utf8(three[..header_end].to_vec()).expect("text");
    let two = [header.replace("vertex 3", "vertex 2").as_bytes(), &three[header_end..]].concat();
    std::fs::write(&path, &two).expect("write");
    let row = format!("{} bytes", property_names(0, false).len() * 4);
    for err in [parse_ply(&two, &path).expect_err("whole"), read_ply(&path).expect_err("pieces")] {
        assert_mentions(&err, &["short.ply", "element vertex 2", &row]);
    }
    // ASCII: a row more than declared (blank lines at the end are fine).
    let zeros = "0 ".repeat(14);
    let text = format!("ply\nformat ascii 1.0\nelement vertex 1\n{MIN_PROPS}end_header\n{zeros}\n");
    assert_eq!(parse_ply(format!("{text}\n  \n").as_bytes(), &path).expect("one").len(), 1);
    let err = parse_ply(format!("{text}{zeros}\n").as_bytes(), &path).expect_err("ascii");
    assert_mentions(&err, &["short.ply", "element vertex 1", "14 values on 1 line"]);
    // Elements after the vertices are data the header declares; only what follows them is not.
    let faces = header.replace("end_header", "");
    let faces =
        format!("{faces}element face 1\nproperty list uchar int vertex_indices\nend_header\n");
    let mut bytes = [faces.as_bytes(), &three[header_end + 11..]].concat();
    bytes.push(3);
    [0i32, 1, 2].iter().for_each(|v| bytes.extend(v.to_le_bytes()));
    std::fs::write(&path, &bytes).expect("write");
    assert_eq!(read_ply(&path).expect("faces after the vertices").len(), 3);
    bytes.extend([7u8; 5]);
    std::fs::write(&path, &bytes).expect("write");
    for err in [parse_ply(&bytes, &path).expect_err("whole"), read_ply(&path).expect_err("pieces")]
    {
        assert_mentions(&err, &["short.ply", "element vertex 3", "element face 1", "5 bytes"]);
    }
}

#[test]
fn truncated_data_names_the_vertex() {
    let bytes = encode_ply(&sample(3, 1)).expect("encode");
    let err = parse_ply(&bytes[..bytes.len() - 10], Path::new(P)).expect_err("truncated");
    // The offset is the file's, not the body's.
    let end = format!("ends at byte {}", bytes.len() - 10);
    assert_mentions(&err, &[P, "vertex 2 of 3", "truncated", &end]);
    let text = format!("ply\nformat ascii 1.0\nelement vertex 1\n{MIN_PROPS}end_header\n1 2 3\n");
    let err = parse_ply(text.as_bytes(), Path::new(P)).expect_err("short ascii");
    assert_mentions(&err, &[P, "vertex 0 of 1", "f_dc_0"]);
}

#[test]
fn malformed_headers_are_named() {
    let cases: &[(&str, &[&str])] = &[
        ("PLY\nformat ascii 1.0\nend_header\n", &["not a PLY file"]),
        ("not a ply", &["not a PLY file"]),
        (
            "ply\nformat binary_middle_endian 1.0\nend_header\n",
            &["header line 2", "unsupported format"],
        ),
        ("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", &["no `end_header`"]),
        (
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty half x\nend_header\n",
            &["header line 4", "\"half\""],
        ),
        (
            "ply\nformat ascii 1.0\nproperty float x\nend_header\n",
            &["header line 3", "before any element"],
        ),
        ("ply\nformat ascii 1.0\nelement face 0\nend_header\n", &["no `vertex` element"]),
        ("ply\nelement vertex 0\nend_header\n", &["no `format` line"]),
    ];
    for (text, parts) in cases {
        let err = parse_ply(text.as_bytes(), Path::new(P)).expect_err(text);
        assert_mentions(&err, &[&[P], *parts].concat());
    }
}

#[test]
fn missing_or_odd_properties_are_named() {
    let no_opacity = MIN_PROPS.replace("property float opacity\n", "");
    let text = format!("ply\nformat ascii 1.0\nelement vertex 0\n{no_opacity}end_header\n");
    let err = parse_ply(text.as_bytes(), Path::new(P)).expect_err("no opacity");
    assert_mentions(&err, &[P, "no property `opacity`"]);

    let eight = rest(8).iter().map(|r| format!("property float {r}\n")).collect::<String>();
    let text = format!("ply\nformat ascii 1.0\nelement vertex 0\n{MIN_PROPS}{eight}end_header\n");
    let err = parse_ply(text.as_bytes(), Path::new(P)).expect_err("8 f_rest");
    assert_mentions(&err, &[P, "found 8 f_rest_* properties"]);

    let gap = eight.replace("f_rest_3\n", "f_rest_30\n") + "property float f_rest_8\n";
    let text = format!("ply\nformat ascii 1.0\nelement vertex 0\n{MIN_PROPS}{gap}end_header\n");
    let err = parse_ply(text.as_bytes(), Path::new(P)).expect_err("f_rest gap");
    assert_mentions(&err, &[P, "no property `f_rest_3`"]);

    let twice = format!(
        "ply\nformat ascii 1.0\nelement vertex 0\n{MIN_PROPS}property float x\nend_header\n"
    );
    assert_mentions(
        &parse_ply(twice.as_bytes(), Path::new(P)).expect_err("twice"),
        &[P, "`x` appears twice"],
    );

    let packed = "ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty uint packed_position\nend_header\n";
    let err = parse_ply(packed.as_bytes(), Path::new(P)).expect_err("compressed");
    assert_mentions(&err, &[P, "no property `x`", "compressed PLY"]);

    let text = format!(
        "ply\nformat ascii 1.0\nelement vertex 1\n{MIN_PROPS}property float trgs_population\nend_header\n{}2\n",
        "0 ".repeat(14)
    );
    let err = parse_ply(text.as_bytes(), Path::new(P)).expect_err("population 2");
    assert_mentions(&err, &[P, "vertex 0", "trgs_population is 2"]);
}

#[test]
fn huge_vertex_count_fails_without_allocating() {
    let text = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex 18446744073709551615\n{MIN_PROPS}end_header\n"
    );
    let err = parse_ply(text.as_bytes(), Path::new(P)).expect_err("huge");
    assert_mentions(&err, &[P, "vertex 0 of 18446744073709551615", "truncated"]);
}

#[test]
fn inconsistent_gaussians_are_refused_by_the_writer() {
    let mut g = sample(2, 1);
    g.opacity_logits.pop();
    let dir = scratch_dir("ply-bad");
    let err = write_ply(&dir.join("bad.ply"), &g).expect_err("lengths");
    assert_mentions(&err, &["bad.ply", "opacity_logits"]);
}

/// A big-endian file with its vertices first (read in pieces, unlike the one above).
fn big_endian_vertices(n: usize) -> Vec<u8> {
    let header = format!(
        "ply\nformat binary_big_endian 1.0\nelement face 0\nproperty list uchar int idx\n\
         element vertex {n}\n{MIN_PROPS}property double trgs_reflection\nproperty uchar \
         trgs_population\nend_header\n"
    );
    let mut bytes = header.into_bytes();
    for i in 0..n {
        (0..14).for_each(|k| bytes.extend(value(i, k).to_be_bytes()));
        bytes.extend(f64::from(value(i, 14)).to_be_bytes());
        bytes.push((i % 2) as u8);
    }
    bytes
}

#[test]
fn reading_in_pieces_is_parsing_whole() {
    let mut files: Vec<Vec<u8>> =
        (0..=3).map(|d| encode_ply(&sample(10, d)).expect("encode")).collect();
    let mut props = names(&["x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"]);
    props.extend(rest(9));
    props.extend(names(&[
        "opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3",
    ]));
    files.push(emulate(&["a comment"], &props, 7));
    files.push(big_endian_vertices(8));
    files.push(encode_ply(&Gaussians::empty(2)).expect("encode"));
    // Cut at every byte of the header and at every few bytes of the body: truncated rows, in the
    // first piece and in later ones, and headers that end early.
    let whole = files.clone();
    for file in &whole {
        let cuts = (0..file.len()).filter(|&c| c < 700 || c % 7 == 0 || file.len() - c < 9);
        files.extend(cuts.map(|c| file[..c].to_vec()));
    }
    files.extend(
        [
            // Read whole: ASCII, a list before the vertices, a list among them, no vertices.
            "ply\nformat ascii 1.0\nelement vertex 1\nPROPS end_header\n1 2 3 4 5 6 7 8 9 1 2 3 4 5\n",
            "ply\nformat binary_little_endian 1.0\nelement f 1\nproperty list uchar int i\n\
             element vertex 1\nPROPS end_header\n\x00",
            "ply\nformat binary_little_endian 1.0\nelement vertex 1\nPROPS property list uchar \
             int i\nend_header\n\x00",
            "ply\nformat binary_little_endian 1.0\nelement face 0\nend_header\n",
            // Huge counts and bad values, read in pieces.
            "ply\nformat binary_little_endian 1.0\nelement vertex 18446744073709551615\nPROPS end_header\n",
            "ply\nformat binary_little_endian 1.0\nelement vertex 1\nPROPS property uchar \
             trgs_population\nend_header\n0123456789abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVW\x02",
            "not a ply",
            "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nend_header\n",
        ]
        .map(|t| t.replace("PROPS ", MIN_PROPS).into_bytes()),
    );
    // The splat files are the ones read in pieces; the rest are read whole.
    let in_pieces = |bytes: &[u8]| {
        let end = bytes.windows(11).position(|w| w == b"end_header\n").expect("header") + 11;
        pieces::vertices_in_pieces(&bytes[..end]).is_some()
    };
    assert!(whole.iter().all(|f| in_pieces(f)));
    let read_whole = files[files.len() - 8..files.len() - 4].iter().all(|f| !in_pieces(f));
    assert!(read_whole, "ASCII, lists and no vertices are read whole");
    let dir = scratch_dir("ply-pieces");
    let path = dir.join(P);
    for (f, bytes) in files.iter().enumerate() {
        std::fs::write(&path, bytes).expect("write");
        let expected = parse_ply(bytes, &path);
        for rows in [1, 3, ROWS_PER_PIECE] {
            let got = pieces::read_in_pieces(&path, rows);
            let same = match (&got, &expected) {
                (Ok(a), Ok(b)) => bits(a) == bits(b),
                (Err(a), Err(b)) => a.to_string() == b.to_string(),
                _ => false,
            };
            assert!(same, "file {f}, {rows} rows a piece: {got:?} against {expected:?}");
        }
    }
}
