//! (Each test binary uses a part of this module.)
#![allow(dead_code)]
//! What the GPU-versus-twin tests share: the tolerance, the value comparison and the scene shape.
use trgs_core::fixtures::SceneSpec;

pub const ATOL: f64 = 1e-5;
pub const RTOL: f64 = 1e-3;

pub fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= ATOL + RTOL * b.abs()
}

/// Count the values outside atol + rtol |cpu| (printing the first few with their pixel, for
/// `channels` values per pixel) and print the worst difference.
pub fn compare_values(what: &str, gpu: &[f32], cpu: &[f64], channels: usize) -> usize {
    assert_eq!(gpu.len(), cpu.len(), "{what}: value counts");
    let (mut bad, mut worst) = (0, 0.0f64);
    for (i, (&g, &c)) in gpu.iter().zip(cpu).enumerate() {
        let g = f64::from(g);
        worst = worst.max((g - c).abs());
        if !close(g, c) {
            if bad < 5 {
                eprintln!("{what}: value {i} (pixel {}): gpu {g} cpu {c}", i / channels.max(1));
            }
            bad += 1;
        }
    }
    eprintln!("{what}: max |gpu - cpu| = {worst:.3e}, {bad} outside tolerance");
    bad
}

/// A random scene at 96x72 with SH degree 3 and 20% glass Gaussians.
pub fn spec(seed: u64, gaussians: usize, planes: usize, angle: f64) -> SceneSpec {
    SceneSpec {
        seed,
        gaussians,
        planes,
        width: 96,
        height: 72,
        view_angle_deg: angle,
        sh_degree: 3,
        glass_fraction: 0.2,
    }
}
