//! A PLY written by another tool (the `plyfile` package, in the INRIA 3DGS layout; see
//! fixtures/make_inria_ply.py) renders the same on the GPU and on the CPU twin.
use trgs_core::io::read_ply;
use trgs_core::pipeline::RenderSettings;
use trgs_core::reference;
use trgs_core::scene::{Camera, Intrinsics, Pose};
use trgs_render::{GpuContext, GpuScene, Layer, RenderOptions, Renderer};

#[test]
fn inria_layout_ply_renders_like_the_reference() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/inria_layout.ply");
    let g = read_ply(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((g.len(), g.sh_degree), (400, 3));
    let camera =
        Camera::new("origin", Intrinsics::from_fov_x(70f64.to_radians(), 96, 72), Pose::default());
    let ctx = GpuContext::new().unwrap_or_else(|e| panic!("{e}"));
    let scene = GpuScene::upload(&ctx, &g, &[]).expect("valid model");
    let frame =
        Renderer::new(&ctx).render(&scene, &camera, &RenderOptions::default()).expect("render");
    let gpu = frame.read_layer(&ctx, Layer::Color).expect("readback");
    let cpu = reference::render(&g.cast::<f64>(), &[], &camera, &RenderSettings::default())
        .expect("reference");
    let mut worst = 0.0f64;
    let mut bad = 0;
    for (&a, &b) in gpu.data.iter().zip(&cpu.color.data) {
        let d = (f64::from(a) - b).abs();
        worst = worst.max(d);
        if d > 1e-5 + 1e-3 * b.abs() {
            bad += 1;
        }
    }
    let lit = cpu.alpha.data.iter().filter(|&&a| a > 0.5).count();
    eprintln!(
        "INRIA PLY: max |gpu - cpu| = {worst:.3e}, {bad} values outside tolerance, {lit} pixels with alpha > 0.5"
    );
    assert!(lit > 1000, "the fixture should cover the image");
    assert!(bad as f64 <= 1e-3 * gpu.data.len() as f64, "{bad} values differ");
}
