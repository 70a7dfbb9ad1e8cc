//! Unit tests of `run::checkpoint`: exact round trips, a bad state not written over a good one,
//! truncated and foreign files named.
use super::*;

fn sample() -> Checkpoint {
    let mut rng = trgs_core::rng::Rng::new(3);
    let mut g = Gaussians::<f32>::zeros(5, 1);
    for x in g.means.iter_mut().flatten() {
        *x = rng.range(-1.0, 1.0) as f32;
    }
    g.rotations.fill([1.0, 0.0, 0.0, 0.0]);
    g.populations[2] = Population::Glass;
    let widths = attribute_widths(g.sh_coeffs());
    let m = PerAttribute::from_fn(|a| (0..5 * widths[a]).map(|i| i as f32 * 0.5).collect());
    let v = m.clone().map(|a: Vec<f32>| a.iter().map(|x| x * x).collect());
    let plane = ReflectionPlane::new(
        DVec3::new(0.1, 0.2, 0.3),
        DVec3::new(0.0, 0.0, 2.0),
        DVec3::X,
        1.5,
        0.7,
        Material::Mirror,
    );
    Checkpoint {
        step: 42,
        state: TrainState { gaussians: g, m, v },
        planes: vec![plane],
        plane_moments: vec![PlaneMoments {
            m: [0.25; 7],
            v: [1e-9; 7],
            steps: 17,
            offset_limit: Some(OffsetLimit { anchor: [0.5, -1.0, 2.0], tolerance: 0.03 }),
        }],
        exposures: {
            let mut e = ViewExposures::default();
            e.step("view_003", &[[0.5, -0.25, 0.0, 1.0]; 3], 0.01);
            e.step("view_004", &[[-0.5, 0.25, 0.0, 1.0]; 3], 0.01);
            e
        },
        densify_stats: Some(DensifyStats {
            grad_sum: vec![1.0, 2.0, 3.0, 4.0, 5.0],
            count: vec![1, 2, 3, 4, 5],
            max_radius: vec![0.5; 5],
        }),
        rng_state: 0xdead_beef,
        extra: serde_json::json!({"order": [3, 1, 2]}),
    }
}

/// A checkpoint path in a scratch folder that lives as long as the returned guard.
fn scratch(tag: &str) -> (trgs_core::scratch::ScratchDir, std::path::PathBuf) {
    let dir = trgs_core::scratch::ScratchDir::new(&format!("ckpt-{tag}"));
    let path = dir.join(CHECKPOINT_FILE);
    (dir, path)
}

#[test]
fn round_trip_is_exact() {
    let (_dir, path) = scratch("rt");
    let ck = sample();
    write_checkpoint(&path, &ck).expect("write");
    let back = read_checkpoint(&path).expect("read");
    assert_eq!(back.step, ck.step);
    assert_eq!(back.state.gaussians, ck.state.gaussians);
    assert_eq!(back.state.m, ck.state.m);
    assert_eq!(back.state.v, ck.state.v);
    assert_eq!(back.planes, ck.planes);
    assert_eq!(back.plane_moments, ck.plane_moments);
    assert_eq!(back.exposures, ck.exposures);
    assert_eq!(back.densify_stats, ck.densify_stats);
    assert_eq!(back.rng_state, ck.rng_state);
    assert_eq!(back.extra, ck.extra);
}

#[test]
fn a_state_that_cannot_be_resumed_is_not_written_over_a_good_one() {
    let (_dir, path) = scratch("diverged");
    let good = sample();
    write_checkpoint(&path, &good).expect("write");
    let before = std::fs::read(&path).expect("read back");
    type Spoil = fn(&mut TrainState);
    let cases: [(&str, Spoil); 3] = [
        ("Gaussian 1: mean is not finite", |s| s.gaussians.means[1][2] = f32::NAN),
        ("Gaussian 0: rotation (zero quaternion)", |s| s.gaussians.rotations[0] = [0.0; 4]),
        ("Gaussian 4: the second Adam moment of sh", |s| {
            let sh = &mut s.v[Attribute::Sh];
            let k = sh.len() - 1;
            sh[k] = f32::INFINITY;
        }),
    ];
    for (expected, spoil) in cases {
        let mut bad = sample();
        bad.step += 100;
        spoil(&mut bad.state);
        let err = write_checkpoint(&path, &bad).expect_err(expected).to_string();
        assert!(err.contains(expected) && err.contains("not written"), "{err}");
        assert!(err.contains(&format!("after step {}", bad.step)), "{err}");
        assert_eq!(std::fs::read(&path).expect("read back"), before, "{expected}");
    }
    assert_eq!(read_checkpoint(&path).expect("read").step, good.step);
}

#[test]
fn truncated_and_foreign_files_are_named_errors() {
    let (_dir, path) = scratch("bad");
    write_checkpoint(&path, &sample()).expect("write");
    let bytes = std::fs::read(&path).expect("read back");
    std::fs::write(&path, &bytes[..bytes.len() - 10]).expect("truncate");
    let err = read_checkpoint(&path).expect_err("truncated").to_string();
    assert!(err.contains("truncated") && err.contains(CHECKPOINT_FILE), "{err}");
    std::fs::write(&path, [&bytes[..], b"\0\0\0"].concat()).expect("lengthen");
    let err = read_checkpoint(&path).expect_err("lengthened").to_string();
    assert!(err.contains("3 bytes after the last array"), "{err}");
    // A manifest that promises more than the file holds is refused before it is allocated.
    let text = String::from_utf8_lossy(&bytes).into_owned();
    let means = r#"["means","f32",15]"#;
    assert!(text.contains(means), "the sample's manifest names its means");
    let huge = text.replacen(means, r#"["means","f32",1000000000000]"#, 1);
    std::fs::write(&path, huge.as_bytes()).expect("inflate");
    let err = read_checkpoint(&path).expect_err("inflated").to_string();
    assert!(err.contains("array means: expected 1000000000000 f32 values"), "{err}");
    std::fs::write(&path, MAGIC).expect("magic only");
    let err = read_checkpoint(&path).expect_err("no header").to_string();
    assert!(err.contains("no header line"), "{err}");
    std::fs::write(&path, b"ply\nformat binary_little_endian 1.0\n").expect("foreign");
    let err = read_checkpoint(&path).expect_err("foreign").to_string();
    assert!(err.contains("not a trgs checkpoint"), "{err}");
    // Another format version is said to be one, not "not a checkpoint".
    std::fs::write(&path, b"trgs-checkpoint 2\n{}\n").expect("newer");
    let err = read_checkpoint(&path).expect_err("newer").to_string();
    assert!(err.contains("format version 2, written by a newer trgs"), "{err}");
    std::fs::write(&path, b"trgs-checkpoint 0\n{}\n").expect("older");
    let err = read_checkpoint(&path).expect_err("older").to_string();
    assert!(err.contains("format version 0, which this trgs (version 1) no longer"), "{err}");
    // A hand-edited offset limit that would break the plane step is refused on reading.
    let mut ck = sample();
    ck.plane_moments[0].offset_limit =
        Some(OffsetLimit { anchor: [0.0, 0.0, 0.0], tolerance: -0.01 });
    write_checkpoint(&path, &ck).expect("write");
    let err = read_checkpoint(&path).expect_err("negative tolerance").to_string();
    assert!(err.contains("plane 0: offset limit") && err.contains(CHECKPOINT_FILE), "{err}");
}
