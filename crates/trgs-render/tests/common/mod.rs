//! (Each test binary uses a part of this module.)
#![allow(dead_code)]
//! What the GPU-versus-twin tests share: the tolerance, the value comparison and the scene shape.
use glam::DVec2;
use trgs_core::Image;
use trgs_core::fixtures::SceneSpec;
use trgs_core::reference::Projected;
use trgs_core::reference::{Frame, FrameGrads};
use trgs_core::rng::Rng;
use trgs_render::toolkit::layout::{
    FLAG_CLAMPED_B, FLAG_CLAMPED_G, FLAG_CLAMPED_R, FLAG_GLASS, FLAG_VISIBLE, ProjectedGaussian,
};
use trgs_render::{DeviceOptions, GpuContext, TileLayout};

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

/// The adapter's features with each replay layout (one pixel per thread is what a GPU runs,
/// several rows what a CPU adapter runs), one pixel per thread without the block walk as well
/// (what a GPU runs: the passes' batches in workgroup memory with subgroup reductions), and the
/// fallback without the features.
pub fn contexts() -> Vec<(&'static str, GpuContext)> {
    let fast = DeviceOptions { poison_fresh_buffers: true, ..Default::default() };
    let layout = |l| DeviceOptions { tile_layout: Some(l), ..fast.clone() };
    let as_on_a_gpu =
        DeviceOptions { block_walk: Some(false), ..layout(TileLayout::PixelPerThread) };
    let fallback = DeviceOptions { disable_optional_features: true, ..fast.clone() };
    vec![
        ("native, one pixel per thread", layout(TileLayout::PixelPerThread)),
        ("native, one pixel per thread, no block walk", as_on_a_gpu),
        ("native, rows per thread", layout(TileLayout::RowsPerThread)),
        ("fallback", fallback),
    ]
    .into_iter()
    .map(|(n, o)| (n, GpuContext::with_options(&o).unwrap_or_else(|e| panic!("{e}"))))
    .collect()
}

/// Pixels of up to four single- or multi-channel images packed as vec4 per pixel.
pub fn pack(parts: &[(&Image<f64>, usize)]) -> Vec<[f32; 4]> {
    let (w, h) = (parts[0].0.width, parts[0].0.height);
    let mut out = vec![[0.0f32; 4]; (w * h) as usize];
    for &(im, first) in parts {
        for y in 0..h {
            for x in 0..w {
                for c in 0..im.channels {
                    out[(y * w + x) as usize][first + c as usize] = im.get(x, y, c) as f32;
                }
            }
        }
    }
    out
}

/// [`compare_values`] of single values.
pub fn compare(what: &str, gpu: &[f32], cpu: &[f64]) -> usize {
    compare_values(what, gpu, cpu, 1)
}

/// The `channels` of each packed pixel, in order.
pub fn channel(v: &[[f32; 4]], channels: std::ops::Range<usize>) -> Vec<f32> {
    v.iter().flat_map(|p| p[channels.clone()].to_vec()).collect()
}

/// Random upstream gradients in [-1, 1] for every layer of `frame`.
pub fn random_grads(seed: u64, frame: &Frame, planes: usize) -> FrameGrads {
    let mut rng = Rng::new(seed);
    FrameGrads::filled(frame.width(), frame.height(), planes, |im| {
        for v in &mut im.data {
            *v = rng.range(-1.0, 1.0);
        }
    })
}
