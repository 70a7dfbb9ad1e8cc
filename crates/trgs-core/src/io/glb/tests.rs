use super::read::{chunks, read_accessor, word};
use super::*;
use crate::io::test_util::{assert_mentions, scratch_dir};
use crate::rng::Rng;
use crate::scene::Population;
use glam::DVec3;

fn random_gaussians(n: usize, degree: u32, rng: &mut Rng) -> Gaussians<f32> {
    let mut g = Gaussians::<f32>::zeros(n, degree);
    let r = |rng: &mut Rng, lo: f64, hi: f64| rng.range(lo, hi) as f32;
    for i in 0..n {
        g.means[i] = [r(rng, -5.0, 5.0), r(rng, -5.0, 5.0), r(rng, 0.0, 9.0)];
        // Unnormalised, as training leaves them.
        g.rotations[i] = [0; 4].map(|_| r(rng, -2.0, 2.0));
        g.log_scales[i] = [0; 3].map(|_| r(rng, -9.0, 2.0));
        // Logits far into the sigmoid's flat ends, where an f32 opacity loses them.
        g.opacity_logits[i] = r(rng, -14.0, 14.0);
        g.mask_logits[i] = r(rng, -3.0, 3.0);
        g.log_reflections[i] = r(rng, -1.0, 1.0);
        if i % 5 == 0 {
            g.populations[i] = Population::Glass;
        }
    }
    for v in g.sh.iter_mut().flatten() {
        *v = r(rng, -1.5, 1.5);
    }
    g
}

fn planes() -> Vec<ReflectionPlane> {
    let mut glass = ReflectionPlane::new(
        DVec3::new(1.08, -1.53, 1.77),
        DVec3::new(-0.08, 0.086, -0.99),
        DVec3::new(0.94, 0.33, -0.05),
        1.6,
        1.0,
        Material::Glass,
    );
    glass.r0_logit = -1.234_567_890_123;
    let mirror = ReflectionPlane::new(
        DVec3::new(-2.0, 0.5, 3.0),
        DVec3::new(1.0, 0.0, 0.2),
        DVec3::Y,
        0.7,
        1.9,
        Material::Mirror,
    );
    vec![glass, mirror]
}

/// The JSON document of a GLB and its BIN chunk.
fn split(bytes: &[u8]) -> (Value, Vec<u8>) {
    let (doc, bin) = chunks(bytes).expect("a GLB");
    (doc, bin.to_vec())
}

/// A GLB with the same BIN chunk and an edited document.
fn rebuild(bytes: &[u8], edit: impl FnOnce(&mut Value)) -> Vec<u8> {
    let (mut doc, bin) = split(bytes);
    edit(&mut doc);
    assemble(&doc, &bin)
}

/// The GLB bytes of a document and a BIN chunk.
fn assemble(doc: &Value, bin: &[u8]) -> Vec<u8> {
    let mut text = serde_json::to_vec(doc).expect("json");
    text.resize(text.len().next_multiple_of(4), b' ');
    let total = (12 + 8 + text.len() + 8 + bin.len()) as u32;
    let mut out = Vec::new();
    for w in [MAGIC, 2, total, text.len() as u32, CHUNK_JSON] {
        out.extend(w.to_le_bytes());
    }
    out.extend(&text);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(CHUNK_BIN.to_le_bytes());
    out.extend(bin);
    out
}

/// Where the first value of a mesh attribute lies in the whole GLB's bytes.
fn attribute_offset(bytes: &[u8], attribute: &str) -> usize {
    let (doc, bin) = split(bytes);
    let acc = &doc["meshes"][0]["primitives"][0]["attributes"][attribute];
    let acc = &doc["accessors"][acc.as_u64().expect("accessor") as usize];
    let view = &doc["bufferViews"][acc["bufferView"].as_u64().expect("view") as usize];
    let in_view = acc["byteOffset"].as_u64().unwrap_or(0);
    bytes.len() - bin.len() + (view["byteOffset"].as_u64().unwrap_or(0) + in_view) as usize
}

fn unit(q: [f32; 4]) -> [f32; 4] {
    let n = q.iter().map(|v| v * v).sum::<f32>().sqrt();
    let s = if q[0] < 0.0 { -1.0 } else { 1.0 };
    q.map(|v| s * v / n)
}

#[test]
fn round_trip_is_lossless() {
    let dir = scratch_dir("glb-round-trip");
    let mut rng = Rng::new(17);
    for degree in 0..=3 {
        let g = random_gaussians(257, degree, &mut rng);
        let path = dir.join(format!("model{degree}.glb"));
        write_glb(&path, &g, &planes()).expect("write");
        let (back, back_planes) = read_glb(&path).expect("read");
        assert_eq!(back.sh_degree, degree);
        assert_eq!(back.means, g.means);
        assert_eq!(back.sh, g.sh);
        assert_eq!(back.opacity_logits, g.opacity_logits);
        assert_eq!(back.mask_logits, g.mask_logits);
        assert_eq!(back.log_reflections, g.log_reflections);
        assert_eq!(back.populations, g.populations);
        for (a, b) in back.log_scales.iter().flatten().zip(g.log_scales.iter().flatten()) {
            // ln(exp(x)) in f32: the scale itself to an ulp or two.
            assert!((a - b).abs() <= 2e-7 * b.abs().max(1.0), "log scale {a} vs {b}");
        }
        for (a, b) in back.rotations.iter().zip(&g.rotations) {
            let (a, b) = (unit(*a), unit(*b));
            for k in 0..4 {
                assert!((a[k] - b[k]).abs() < 1e-6, "rotation {a:?} vs {b:?}");
            }
        }
        assert_eq!(back_planes.len(), 2);
        for (a, b) in back_planes.iter().zip(&planes()) {
            assert_eq!(a.material, b.material);
            assert_eq!(a.r0_logit, b.r0_logit);
            assert_eq!((a.width, a.height), (b.width, b.height));
            assert_eq!((a.centre, a.normal), (b.centre, b.normal));
            assert!((a.axis - b.axis).length() < 1e-15, "{} vs {}", a.axis, b.axis);
        }
    }
}

/// The glTF 2.0 and KHR_gaussian_splatting rules a validator checks: container layout, required
/// properties, attribute types and counts, POSITION bounds, value ranges, buffer alignment.
#[test]
fn a_ply_model_converts_to_glb_and_reads_back() {
    let dir = scratch_dir("glb-from-ply");
    let g = random_gaussians(40, 3, &mut Rng::new(61));
    crate::io::write_ply(&dir.join("m.ply"), &g).expect("write the PLY");
    let from_ply = crate::io::read_ply(&dir.join("m.ply")).expect("read the PLY");
    write_glb(&dir.join("m.glb"), &from_ply, &planes()).expect("write the GLB");
    let (back, planes_back) = read_glb(&dir.join("m.glb")).expect("read the GLB");
    assert_eq!(planes_back.len(), 2);
    assert_eq!((back.len(), back.sh_degree), (40, 3));
    assert_eq!((back.means.clone(), back.sh.clone()), (g.means.clone(), g.sh.clone()));
    assert_eq!(back.opacity_logits, g.opacity_logits);
    for (a, b) in back.log_scales.iter().flatten().zip(g.log_scales.iter().flatten()) {
        assert!((a - b).abs() < 1e-5, "log-scale {a} against {b}");
    }
}

#[test]
fn values_a_model_cannot_hold_are_refused_both_ways() {
    let path = Path::new("m.glb");
    let g = random_gaussians(3, 1, &mut Rng::new(5));
    let good = encode_glb(&g, &[]).expect("encode");
    let with = |attribute: &str, k: usize, v: f32| {
        let mut bad = good.clone();
        let at = attribute_offset(&good, attribute) + 4 * k;
        bad[at..at + 4].copy_from_slice(&v.to_le_bytes());
        bad
    };
    // Green of Gaussian 1's second SH coefficient, and Gaussian 2's log reflection.
    let sh = with("KHR_gaussian_splatting:SH_DEGREE_1_COEF_0", 3 + 1, f32::NAN);
    let err = parse_glb(&sh, path).expect_err("NaN");
    assert_mentions(&err, &["m.glb", "Gaussian 1", "SH_DEGREE_1_COEF_0[1] = NaN"]);
    let reflection = with("_TRGS_LOG_REFLECTION", 2, 1e20);
    let err = parse_glb(&reflection, path).expect_err("huge");
    assert_mentions(&err, &["Gaussian 2", "_TRGS_LOG_REFLECTION = 1e20", "exp"]);
    // The largest scale f32 holds reads as a log-scale whose exp is finite.
    let (big, _) =
        parse_glb(&with("KHR_gaussian_splatting:SCALE", 0, f32::MAX), path).expect("max");
    assert!(big.log_scales[0][0] > 88.0 && big.log_scales[0][0].exp().is_finite());
    // What cannot be stored is not written: a zero quaternion has no direction to store.
    let mut zero = g.clone();
    zero.rotations[1] = [0.0; 4];
    assert_mentions(&encode_glb(&zero, &[]).expect_err("zero"), &["Gaussian 1", "unit quaternion"]);
}

#[test]
fn the_file_follows_the_extension_rules() {
    let mut rng = Rng::new(3);
    let g = random_gaussians(101, 3, &mut rng);
    let bytes = encode_glb(&g, &planes()).expect("encode");
    assert_eq!(word(&bytes, 8), Some(bytes.len() as u32), "header length");
    let json_len = word(&bytes, 12).expect("chunk") as usize;
    assert_eq!(json_len % 4, 0);
    let text = &bytes[20..20 + json_len];
    let end = text.iter().rposition(|&b| b != b' ').expect("text");
    assert_eq!(text[end], b'}', "the JSON chunk is padded with spaces only");
    let bin_len = word(&bytes, 20 + json_len).expect("bin chunk") as usize;
    assert_eq!(bin_len % 4, 0);
    assert_eq!(word(&bytes, 24 + json_len), Some(CHUNK_BIN));
    assert_eq!(bytes.len(), 28 + json_len + bin_len);

    let (doc, bin) = split(&bytes);
    assert_eq!(doc["asset"]["version"], "2.0");
    assert!(doc["extensionsUsed"].as_array().expect("list").contains(&json!(EXTENSION)));
    let byte_length = doc["buffers"][0]["byteLength"].as_u64().expect("length") as usize;
    assert!(
        doc["buffers"][0]["uri"].is_null()
            && byte_length <= bin.len()
            && bin.len() < byte_length + 4
    );
    let prim = &doc["meshes"][0]["primitives"][0];
    assert_eq!(prim["mode"], 0);
    let ext = &prim["extensions"][EXTENSION];
    assert_eq!(ext["kernel"], "ellipse");
    assert!(ext["colorSpace"].is_string());

    let mut required = vec![
        ("POSITION".to_string(), "VEC3"),
        ("KHR_gaussian_splatting:ROTATION".to_string(), "VEC4"),
        ("KHR_gaussian_splatting:SCALE".to_string(), "VEC3"),
        ("KHR_gaussian_splatting:OPACITY".to_string(), "SCALAR"),
    ];
    for l in 0..=3u32 {
        for n in 0..2 * l + 1 {
            required.push((format!("KHR_gaussian_splatting:SH_DEGREE_{l}_COEF_{n}"), "VEC3"));
        }
    }
    let attrs = prim["attributes"].as_object().expect("attributes");
    for (name, kind) in &required {
        let acc = &doc["accessors"][attrs[name].as_u64().expect(name) as usize];
        assert_eq!(acc["type"], *kind, "{name}");
    }
    let values = |name: &str| -> Vec<f32> {
        read_accessor(&doc, &bin, &attrs[name], name, &["SCALAR", "VEC3", "VEC4"], None)
            .expect(name)
            .0
    };
    for (name, index) in attrs {
        assert!(
            name.starts_with("KHR_gaussian_splatting:")
                || name.starts_with('_')
                || ["POSITION", "COLOR_0"].contains(&name.as_str()),
            "{name}: application attributes must start with an underscore"
        );
        let acc = &doc["accessors"][index.as_u64().expect("index") as usize];
        assert_eq!(acc["componentType"], 5126, "{name}");
        assert_eq!(acc["count"], 101, "{name}: every attribute has the same count");
        let view = &doc["bufferViews"][acc["bufferView"].as_u64().expect("view") as usize];
        let offset = view["byteOffset"].as_u64().expect("offset") as usize;
        let len = view["byteLength"].as_u64().expect("len") as usize;
        let width = components(acc["type"].as_str().expect("type")).expect("known type");
        assert_eq!(offset % 4, 0, "{name}: 4-byte aligned");
        assert_eq!(view["target"], 34962, "{name}: a vertex attribute's view is ARRAY_BUFFER");
        assert_eq!(len, 101 * width * 4, "{name}");
        assert!(offset + len <= byte_length, "{name}: inside the buffer");
    }
    let pos = values("POSITION");
    let acc = &doc["accessors"][attrs["POSITION"].as_u64().expect("index") as usize];
    for a in 0..3 {
        let axis: Vec<f32> = pos.iter().skip(a).step_by(3).copied().collect();
        let lo = axis.iter().copied().fold(f32::INFINITY, f32::min);
        let hi = axis.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        assert_eq!(acc["min"][a].as_f64(), Some(f64::from(lo)));
        assert_eq!(acc["max"][a].as_f64(), Some(f64::from(hi)));
    }
    for q in values("KHR_gaussian_splatting:ROTATION").chunks(4) {
        let norm = q.iter().map(|v| v * v).sum::<f32>().sqrt();
        assert!((norm - 1.0).abs() < 1e-6, "unit quaternions: {q:?}");
    }
    assert!(values("KHR_gaussian_splatting:SCALE").iter().all(|&s| s >= 0.0));
    assert!(values("KHR_gaussian_splatting:OPACITY").iter().all(|o| (0.0..=1.0).contains(o)));
    assert!(values("COLOR_0").iter().all(|c| (0.0..=1.0).contains(c)));
    // COLOR_0 is linear: the DC colour (sRGB, as 3DGS trains it) decoded.
    for (i, c) in values("COLOR_0").chunks(3).enumerate() {
        let srgb = g.sh[i * g.sh_coeffs()].map(|v| (0.5 + C0 as f32 * v).clamp(0.0, 1.0));
        for ch in 0..3 {
            let want = if srgb[ch] <= 0.04045 {
                srgb[ch] / 12.92
            } else {
                ((srgb[ch] + 0.055) / 1.055).powf(2.4)
            };
            assert!((c[ch] - want).abs() < 1e-6, "{c:?} for sRGB {srgb:?}");
        }
    }
    // The plane nodes hang under the root with their transform and extras.
    let root = &doc["nodes"][doc["scenes"][0]["nodes"][0].as_u64().expect("root") as usize];
    assert_eq!(root["children"].as_array().expect("children").len(), 3);
    assert!(!doc["nodes"][2]["extras"]["trgs_plane"].is_null());
}

#[test]
fn a_file_from_another_tool_reads_with_defaults() {
    let mut rng = Rng::new(4);
    let mut g = random_gaussians(40, 1, &mut rng);
    g.opacity_logits.iter_mut().for_each(|l| *l = l.clamp(-5.0, 5.0));
    let bytes = rebuild(&encode_glb(&g, &[]).expect("encode"), |doc| {
        let attrs = doc["meshes"][0]["primitives"][0]["attributes"].as_object_mut().expect("map");
        attrs.retain(|name, _| !name.starts_with('_'));
    });
    let (back, planes) = parse_glb(&bytes, Path::new("other.glb")).expect("read");
    assert!(planes.is_empty());
    assert!(back.populations.iter().all(|&p| p == Population::Primary));
    assert!(back.log_reflections.iter().all(|&v| v == 0.0));
    for (a, b) in back.opacity_logits.iter().zip(&g.opacity_logits) {
        assert!((a - b).abs() < 1e-3, "logit {a} vs {b}");
    }
}

#[test]
fn malformed_files_get_named_errors() {
    let mut rng = Rng::new(5);
    let g = random_gaussians(10, 1, &mut rng);
    let good = encode_glb(&g, &planes()).expect("encode");
    let path = Path::new("scene/model.glb");
    let cases: Vec<(Vec<u8>, &str)> = vec![
        (b"PLY\n....".to_vec(), "no 'glTF' magic"),
        (good[..good.len() - 100].to_vec(), "claims"),
        (
            rebuild(&good, |d| {
                d["meshes"][0]["primitives"][0]["attributes"]
                    .as_object_mut()
                    .expect("map")
                    .remove("KHR_gaussian_splatting:ROTATION");
            }),
            "no KHR_gaussian_splatting:ROTATION attribute",
        ),
        (
            rebuild(&good, |d| {
                d["meshes"][0]["primitives"][0]["attributes"]
                    .as_object_mut()
                    .expect("map")
                    .remove("KHR_gaussian_splatting:SH_DEGREE_1_COEF_2");
            }),
            "SH degree 1 is partly defined",
        ),
        (rebuild(&good, |d| d["meshes"][0]["primitives"][0]["mode"] = json!(4)), "POINTS"),
        (
            rebuild(&good, |d| {
                d["meshes"][0]["primitives"][0]["extensions"][EXTENSION]
                    .as_object_mut()
                    .expect("map")
                    .remove("colorSpace");
            }),
            "colorSpace",
        ),
        (rebuild(&good, |d| d["accessors"][1]["componentType"] = json!(5125)), "float (5126)"),
        (rebuild(&good, |d| d["accessors"][2]["count"] = json!(9)), "9 elements"),
        // Corrupt sizes are errors before anything is allocated or an offset overflows.
        (
            rebuild(&good, |d| d["accessors"][0]["count"] = json!(1_000_000_000_000_000u64)),
            "past the BIN chunk",
        ),
        (
            rebuild(&good, |d| d["bufferViews"][0]["byteOffset"] = json!(u64::MAX)),
            "past the BIN chunk",
        ),
        (rebuild(&good, |d| d["bufferViews"][0]["byteStride"] = json!(0)), "byteStride 0"),
        (
            rebuild(&good, |d| d["nodes"][2]["extras"]["trgs_plane"]["material"] = json!("chrome")),
            "chrome",
        ),
        (
            rebuild(&good, |d| d["nodes"][2]["extras"]["trgs_plane"]["normal"] = json!([0, 0, 0])),
            "normal",
        ),
    ];
    for (bytes, expected) in cases {
        let err = parse_glb(&bytes, path).expect_err(expected);
        assert_mentions(&err, &["scene/model.glb", expected]);
    }
    // Values written into the BIN chunk in place: a population other than 0 (primary) or 1
    // (glass), a zero quaternion, a negative or infinite scale.
    let with = |attribute: &str, values: &[f32]| {
        let mut bad = good.clone();
        let at = attribute_offset(&good, attribute);
        for (k, v) in values.iter().enumerate() {
            bad[at + 4 * k..at + 4 * k + 4].copy_from_slice(&v.to_le_bytes());
        }
        bad
    };
    let cases = [
        ("_TRGS_POPULATION", vec![2.0], "Gaussian 0: _TRGS_POPULATION 2, expected 0 or 1"),
        ("KHR_gaussian_splatting:ROTATION", vec![0.0; 4], "Gaussian 0: rotation [0.0, 0.0"),
        ("KHR_gaussian_splatting:SCALE", vec![-1.0], "Gaussian 0: scale -1"),
        ("KHR_gaussian_splatting:SCALE", vec![f32::INFINITY], "Gaussian 0: scale inf"),
    ];
    for (attribute, values, expected) in cases {
        let err = parse_glb(&with(attribute, &values), path).expect_err(expected);
        assert_mentions(&err, &["scene/model.glb", expected]);
    }
    // A zero scale (a flat splat) reads as the smallest normal scale, not as ln(0).
    let (flat, _) = parse_glb(&with("KHR_gaussian_splatting:SCALE", &[0.0]), path).expect("flat");
    assert_eq!(flat.log_scales[0][0], f32::MIN_POSITIVE.ln());
    assert!(flat.log_scales.iter().flatten().all(|v| v.is_finite()));
    let empty = Gaussians::<f32>::zeros(0, 0);
    assert!(encode_glb(&empty, &[]).is_err(), "a point primitive needs a point");
}

/// The covariance R S S R^T of Gaussian `i` (f64), for comparing placements.
fn covariance(g: &Gaussians<f32>, i: usize) -> DMat3 {
    let [w, x, y, z] = g.rotations[i].map(f64::from);
    let r = DMat3::from_quat(DQuat::from_xyzw(x, y, z, w).normalize());
    let s = DMat3::from_diagonal(DVec3::from_array(g.log_scales[i].map(|v| f64::from(v).exp())));
    r * s * s * r.transpose()
}

#[test]
fn a_y_up_file_without_trgs_root_is_turned_into_trgs_frame_with_its_sh() {
    // Another tool's file: the Gaussians in glTF's y-up frame under an identity node. trgs's
    // frame is y down, z forward: the same Gaussians with y and z negated, and their colours
    // seen along the flipped directions.
    let mut rng = Rng::new(8);
    let g = random_gaussians(12, 3, &mut rng);
    let bytes = rebuild(&encode_glb(&g, &[]).expect("encode"), |doc| {
        doc["nodes"][0]["rotation"] = json!([0.0, 0.0, 0.0, 1.0]);
    });
    let (back, _) = parse_glb(&bytes, Path::new("yup.glb")).expect("read");
    // A mesh that no node places is in glTF's frame too.
    let unplaced = rebuild(&encode_glb(&g, &[]).expect("encode"), |doc| {
        doc["nodes"][1].as_object_mut().expect("node").remove("mesh");
    });
    let (loose, _) = parse_glb(&unplaced, Path::new("loose.glb")).expect("read");
    assert_eq!(loose.means, back.means);
    let flip = DMat3::from_diagonal(DVec3::new(1.0, -1.0, -1.0));
    let k = g.sh_coeffs();
    for i in 0..g.len() {
        let [x, y, z] = g.means[i];
        assert_eq!(back.means[i], [x, -y, -z]);
        let want = flip * covariance(&g, i) * flip;
        assert!(covariance(&back, i).abs_diff_eq(
            want,
            1e-4 * want.abs().to_cols_array().iter().fold(1.0, |a, &b| f64::max(a, b))
        ));
        let sh = |h: &Gaussians<f32>| -> Vec<[f64; 3]> {
            h.sh[i * k..(i + 1) * k].iter().map(|c| c.map(f64::from)).collect()
        };
        for d in [[0.3, -0.5, 0.81], [-0.9, 0.1, 0.42], [0.0, 0.6, -0.8]] {
            let flipped = [d[0], -d[1], -d[2]];
            let (a, b) = (crate::sh::eval(3, &sh(&back), flipped), crate::sh::eval(3, &sh(&g), d));
            for c in 0..3 {
                assert!((a[c] - b[c]).abs() < 1e-5, "Gaussian {i}: colour {a:?} against {b:?}");
            }
        }
    }
}

#[test]
fn node_transforms_move_scale_and_turn_or_are_refused() {
    let mut rng = Rng::new(9);
    let g = random_gaussians(6, 0, &mut rng);
    // Under trgs's root: a child node that moves, scales by 2 and turns 90 degrees about y.
    let turn = DQuat::from_rotation_y(std::f64::consts::FRAC_PI_2);
    let node = |doc: &mut Value| {
        doc["nodes"][1]["translation"] = json!([1.0, 2.0, 3.0]);
        doc["nodes"][1]["scale"] = json!([2.0, 2.0, 2.0]);
        doc["nodes"][1]["rotation"] = json!([turn.x, turn.y, turn.z, turn.w]);
    };
    let bytes = rebuild(&encode_glb(&g, &[]).expect("encode"), node);
    let (back, _) = parse_glb(&bytes, Path::new("moved.glb")).expect("read");
    // The root's flip is undone by the glTF-to-trgs conversion: in trgs's frame the Gaussians
    // move by the node's own transform.
    let l = DMat3::from_quat(turn) * 2.0;
    let t = DVec3::new(1.0, 2.0, 3.0);
    for i in 0..g.len() {
        let want = l * DVec3::from_array(g.means[i].map(f64::from)) + t;
        let got = DVec3::from_array(back.means[i].map(f64::from));
        assert!(got.abs_diff_eq(want, 1e-4), "{got} against {want}");
        let cov = l * covariance(&g, i) * l.transpose();
        let scale = cov.to_cols_array().iter().fold(1e-12, |a, &b| f64::max(a, b.abs()));
        assert!(covariance(&back, i).abs_diff_eq(cov, 1e-4 * scale));
    }
    // With view-dependent colour the same turn is refused (its SH would need a rotation).
    let g1 = random_gaussians(6, 1, &mut rng);
    let bytes = rebuild(&encode_glb(&g1, &[]).expect("encode"), node);
    let err = parse_glb(&bytes, Path::new("moved.glb")).expect_err("turned SH");
    assert_mentions(&err, &["moved.glb", "SH of degree 1"]);
    // A non-uniform scale cannot be applied to Gaussians exactly.
    let bytes = rebuild(&encode_glb(&g, &[]).expect("encode"), |doc| {
        doc["nodes"][1]["scale"] = json!([1.0, 2.0, 1.0]);
    });
    let err = parse_glb(&bytes, Path::new("squashed.glb")).expect_err("non-uniform");
    assert_mentions(&err, &["squashed.glb", "non-uniform scale"]);
}

#[test]
fn unsupported_features_are_refused_not_misread() {
    let mut rng = Rng::new(10);
    let g = random_gaussians(6, 2, &mut rng);
    let base = encode_glb(&g, &[]).expect("encode");
    // The quantisation extension only allows integer attributes, which trgs decodes.
    let quantised = rebuild(&base, |doc| {
        doc["extensionsRequired"] = json!(["KHR_mesh_quantization", EXTENSION]);
    });
    parse_glb(&quantised, Path::new("q.glb")).expect("KHR_mesh_quantization is fine");
    let required =
        rebuild(&base, |doc| doc["extensionsRequired"] = json!(["EXT_meshopt_compression"]));
    assert_mentions(
        &parse_glb(&required, Path::new("r.glb")).expect_err("required"),
        &["r.glb", "EXT_meshopt_compression"],
    );
    let sparse = rebuild(&base, |doc| {
        let i = doc["meshes"][0]["primitives"][0]["attributes"]["KHR_gaussian_splatting:SCALE"]
            .as_u64()
            .expect("scale accessor") as usize;
        doc["accessors"][i]["sparse"] = json!({"count": 1});
    });
    assert_mentions(
        &parse_glb(&sparse, Path::new("s.glb")).expect_err("sparse"),
        &["s.glb", "SCALE", "sparse"],
    );
    let gap = rebuild(&base, |doc| {
        let attrs = doc["meshes"][0]["primitives"][0]["attributes"].as_object_mut().expect("map");
        attrs.retain(|name, _| !name.contains("SH_DEGREE_1_"));
    });
    assert_mentions(
        &parse_glb(&gap, Path::new("gap.glb")).expect_err("gap"),
        &["gap.glb", "SH_DEGREE_2", "degree 1"],
    );
}

/// `bytes` with the BIN chunk extended by `data` (4-byte aligned) as a new bufferView, and
/// attribute `semantic` pointing at a new accessor over it.
fn with_attribute(bytes: &[u8], semantic: &str, accessor: Value, data: &[u8]) -> Vec<u8> {
    let (mut doc, mut bin) = split(bytes);
    let offset = bin.len();
    bin.extend(data);
    bin.resize(bin.len().next_multiple_of(4), 0);
    let view = doc["bufferViews"].as_array().expect("views").len();
    doc["bufferViews"]
        .as_array_mut()
        .expect("views")
        .push(json!({"buffer": 0, "byteOffset": offset, "byteLength": data.len()}));
    let mut accessor = accessor;
    accessor["bufferView"] = json!(view);
    let index = doc["accessors"].as_array().expect("accessors").len();
    doc["accessors"].as_array_mut().expect("accessors").push(accessor);
    doc["meshes"][0]["primitives"][0]["attributes"][semantic] = json!(index);
    doc["buffers"][0]["byteLength"] = json!(bin.len());
    assemble(&doc, &bin)
}

#[test]
fn quantised_rotations_scales_and_opacities_are_decoded() {
    let mut rng = Rng::new(11);
    let g = random_gaussians(2, 0, &mut rng);
    let base = rebuild(&encode_glb(&g, &[]).expect("encode"), |doc| {
        // Another tool's file: no trgs attributes, so the standard ones are what is read.
        let attrs = doc["meshes"][0]["primitives"][0]["attributes"].as_object_mut().expect("map");
        attrs.retain(|name, _| !name.starts_with('_'));
    });
    // int16 normalised rotations (x y z w): the identity and a half turn about z.
    let rot: Vec<u8> =
        [0i16, 0, 0, 32767, 0, 0, 32767, 0].iter().flat_map(|v| v.to_le_bytes()).collect();
    let acc = json!({"componentType": 5122, "normalized": true, "count": 2, "type": "VEC4"});
    let bytes = with_attribute(&base, "KHR_gaussian_splatting:ROTATION", acc, &rot);
    // uint8 normalised opacities, 4-byte stride (each element aligned as glTF requires).
    let opacity = [255u8, 0, 0, 0, 51, 0, 0, 0];
    let acc = json!({"componentType": 5121, "normalized": true, "count": 2, "type": "SCALAR"});
    let mut bytes = with_attribute(&bytes, "KHR_gaussian_splatting:OPACITY", acc, &opacity);
    let (mut doc, _) = split(&bytes);
    let last = doc["bufferViews"].as_array().expect("views").len() - 1;
    doc["bufferViews"][last]["byteStride"] = json!(4);
    bytes = rebuild(&bytes, |d| *d = doc);
    // uint16 scales, not normalised: whole units.
    let scale: Vec<u8> = [1u16, 2, 3, 4, 5, 6].iter().flat_map(|v| v.to_le_bytes()).collect();
    let acc = json!({"componentType": 5123, "count": 2, "type": "VEC3"});
    let bytes = with_attribute(&bytes, "KHR_gaussian_splatting:SCALE", acc, &scale);
    let (back, _) = parse_glb(&bytes, Path::new("quantised.glb")).expect("read");
    assert_eq!(back.rotations[0], [1.0, 0.0, 0.0, 0.0]);
    assert_eq!(back.rotations[1], [0.0, 0.0, 0.0, 1.0]);
    assert_eq!(back.log_scales[1].map(|v| v.exp().round()), [4.0, 5.0, 6.0]);
    let opacity = |logit: f32| 1.0 / (1.0 + (-logit).exp());
    assert!((opacity(back.opacity_logits[1]) - 0.2).abs() < 1e-5);
    assert!(opacity(back.opacity_logits[0]) > 0.999);
}
