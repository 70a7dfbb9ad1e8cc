//! Stage `opacity_reset` against its twin `opacity_reset_logits`: the opacities capped bit for bit
//! on the GPU, their Adam moments restarted, every other parameter and moment unchanged.
use trgs_core::fixtures::{SceneSpec, random_scene};
use trgs_core::scene::{Attribute, Gaussians, PerAttribute, attribute_widths};
use trgs_render::GpuContext;
use trgs_train::densify::classic::{opacity_reset_cap, opacity_reset_logits};
use trgs_train::stages::GaussianState;
use trgs_train::stages::TrainState;

#[test]
fn the_gpu_caps_as_the_twin_does() {
    let ctx = GpuContext::new().expect("adapter");
    let spec = SceneSpec { gaussians: 2000, sh_degree: 1, ..SceneSpec::default() };
    let mut g: Gaussians<f32> = random_scene(&spec).gaussians.cast();
    let n = g.len();
    for (i, o) in g.opacity_logits.iter_mut().enumerate() {
        *o = (i as f32 / n as f32) * 16.0 - 8.0;
    }
    g.opacity_logits[7] = opacity_reset_cap();
    let w = attribute_widths(g.sh_coeffs());
    let ones = |a: Attribute| vec![1.0f32; n * w[a]];
    let state =
        TrainState { gaussians: g, m: PerAttribute::from_fn(ones), v: PerAttribute::from_fn(ones) };
    let mut gpu = GaussianState::from_state(&ctx, &state, &[]).expect("upload");
    let read_before = ctx.bytes_read();
    gpu.opacity_reset(opacity_reset_cap()).expect("reset");
    assert_eq!(ctx.bytes_read(), read_before, "the reset reads nothing back");
    let got = gpu.read().expect("readback");
    let mut want = state.clone();
    opacity_reset_logits(&mut want.gaussians.opacity_logits);
    assert!(got.gaussians == want.gaussians, "the parameters");
    assert!(
        want.gaussians.opacity_logits.iter().filter(|&&o| o == opacity_reset_cap()).count() > n / 3
    );
    for a in Attribute::ALL {
        let restart = a == Attribute::OpacityLogits;
        let expect = |v: &Vec<f32>| v.iter().all(|&x| x == if restart { 0.0 } else { 1.0 });
        assert!(expect(&got.m[a]) && expect(&got.v[a]), "the moments of {a:?}");
    }
}
