//! (Each test binary uses a part of this module.)
#![allow(dead_code)]
//! What the GPU-versus-twin tests share: the tolerance, the value comparison and the scene shape.
use glam::DVec2;
use trgs_core::fixtures::SceneSpec;
use trgs_core::reference::Projected;
use trgs_render::toolkit::layout::{
    FLAG_CLAMPED_B, FLAG_CLAMPED_G, FLAG_CLAMPED_R, FLAG_GLASS, FLAG_VISIBLE, ProjectedGaussian,
};

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

/// The twin's Projected holding exactly the GPU's values.
pub fn to_reference(p: &[ProjectedGaussian]) -> Projected {
    let mut out = Projected::default();
    for g in p {
        let f = g.flags;
        out.visible.push(f & FLAG_VISIBLE != 0);
        out.mean2d.push(DVec2::new(f64::from(g.mean2d[0]), f64::from(g.mean2d[1])));
        out.conic.push([g.conic[0], g.conic[1], g.conic[2]].map(f64::from));
        out.depth.push(f64::from(g.color[3]));
        out.extent.push(DVec2::new(f64::from(g.extent[0]), f64::from(g.extent[1])));
        out.color.push([g.color[0], g.color[1], g.color[2]].map(f64::from));
        out.color_clamped.push([
            f & FLAG_CLAMPED_R != 0,
            f & FLAG_CLAMPED_G != 0,
            f & FLAG_CLAMPED_B != 0,
        ]);
        out.opacity.push(f64::from(g.conic[3]));
        out.mask.push(f64::from(g.mask));
        out.reflection.push(f64::from(g.reflection));
        out.glass.push(f & FLAG_GLASS != 0);
    }
    out
}
