//! The GPU loss stages (`photometric_loss`, `regularisers`) against their f64 twins in
//! `trgs_core::reference`, on random layers of sizes that do and do not fill the 16x16 workgroups
//! and the blurs' runs of LOSS_BLUR_RUN pixels (one pixel included), with and without glass labels, with every pixel covered by the photo
//! and with a ragged uncovered border (an undistorted photo's). Every gradient buffer starts
//! poison-filled, so a pixel a kernel forgets to write fails the comparison.
use trgs_core::Image;
use trgs_core::pipeline::{DSSIM_LAMBDA, RegulariserWeights};
use trgs_core::reference::{RegulariserInputs, photometric_loss_covered, regularisers, step_guard};
use trgs_core::rng::Rng;
use trgs_render::toolkit::gpu::{self, Recorder};
use trgs_render::{DeviceOptions, GpuContext, LayerGrads};
use trgs_train::stages::{
    ChannelPasses, GpuTarget, LossKernels, LossLayers, LossSettings, LossValues, check_frame_size,
};

const WEIGHTS: RegulariserWeights = RegulariserWeights { depth: 0.3, conflict: 0.7, mask: 0.5 };

struct Layers {
    width: u32,
    height: u32,
    color: Image<f32>,
    target: Image<f32>,
    transmission: Image<f32>,
    alpha: Image<f32>,
    reflection: Image<f32>,
    geometry: Image<f32>,
    hit: Image<u32>,
    annotation: Image<u8>,
    /// A ragged border without a source, for the runs with `partial` coverage.
    covered: Image<u8>,
}

fn random(w: u32, h: u32, channels: u32, rng: &mut Rng) -> Image<f32> {
    let mut im = Image::<f32>::new(w, h, channels);
    im.data.iter_mut().for_each(|v| *v = rng.uniform() as f32);
    im
}

fn levels(mut im: Image<f32>) -> Image<f32> {
    im.data.iter_mut().for_each(|v| *v = (*v * 255.0).round() / 255.0);
    im
}

fn layers(w: u32, h: u32, rng: &mut Rng) -> Layers {
    // Two planes' regions (as their footprints are), a band without a plane, and a few holes:
    // L_c counts where a whole 3x3 window is on one plane, so both the interiors and the
    // outlines are exercised.
    let mut hit = Image::<u32>::new(w, h, 1);
    for (i, v) in hit.data.iter_mut().enumerate() {
        let (x, y) = (i as u32 % w, i as u32 / w);
        let region = if x < w / 6 || y < h / 6 {
            0
        } else if x < w / 2 {
            1
        } else {
            2
        };
        *v = if rng.uniform() < 0.03 { 0 } else { region };
    }
    let mut annotation = Image::<u8>::new(w, h, 1);
    annotation.data.iter_mut().for_each(|v| *v = u8::from(rng.uniform() < 0.5));
    let mut covered = Image::<u8>::new(w, h, 1);
    for (i, v) in covered.data.iter_mut().enumerate() {
        let (x, y) = (i as u32 % w, i as u32 / w);
        *v = u8::from(x > (y * 7) % 4 && y + 2 < h);
    }
    Layers {
        width: w,
        height: h,
        color: random(w, h, 3, rng),
        // On the 8-bit grid, as GpuTarget stores it.
        target: levels(random(w, h, 3, rng)),
        transmission: random(w, h, 3, rng),
        alpha: random(w, h, 1, rng),
        reflection: random(w, h, 3, rng),
        geometry: random(w, h, 3, rng),
        hit,
        annotation,
        covered,
    }
}

/// Pixels as vec4: the channels of `parts` side by side, zero after.
fn vec4s(parts: &[&Image<f32>]) -> Vec<[f32; 4]> {
    let n = (parts[0].width * parts[0].height) as usize;
    let mut out = vec![[0.0f32; 4]; n];
    for (i, px) in out.iter_mut().enumerate() {
        let mut k = 0;
        for im in parts {
            let c = im.channels as usize;
            px[k..k + c].copy_from_slice(&im.data[i * c..(i + 1) * c]);
            k += c;
        }
    }
    out
}

fn f64s(im: &Image<f32>) -> Image<f64> {
    Image {
        width: im.width,
        height: im.height,
        channels: im.channels,
        data: im.data.iter().map(|&v| f64::from(v)).collect(),
    }
}

fn channel(im: &Image<f32>, c: usize) -> Image<f32> {
    let ch = im.channels as usize;
    Image {
        width: im.width,
        height: im.height,
        channels: 1,
        data: im.data.chunks(ch).map(|p| p[c]).collect(),
    }
}

/// The largest |gpu - twin| over the largest |twin| (or over 1e-12 when the twin is zero).
fn relative_error(gpu: &[f32], twin: &[f64]) -> f64 {
    assert_eq!(gpu.len(), twin.len());
    let scale = twin.iter().fold(1e-12f64, |m, v| m.max(v.abs()));
    gpu.iter().zip(twin).map(|(&g, &t)| (f64::from(g) - t).abs()).fold(0.0, f64::max) / scale
}

/// What one recording of the losses gave: their values, the layer gradients they wrote and the
/// strips' sums.
struct Run {
    values: LossValues,
    grads: LayerGrads,
    sums: Vec<[f32; 4]>,
}

fn check(
    ctx: &GpuContext,
    kernels: &mut LossKernels,
    l: &Layers,
    labelled: bool,
    planes: bool,
    partial: bool,
) {
    let tag =
        format!("{}x{} labels {labelled} planes {planes} partial {partial}", l.width, l.height);
    let covered = partial.then_some(&l.covered);
    let run = record_losses(ctx, kernels, l, labelled, planes, covered);
    // What `step_guard` checks: every strip sum finite, and without the regularisers their
    // slot zero (not what an earlier frame or a fresh buffer held).
    assert_eq!(step_guard(0, &run.sums), 0, "{tag}: a strip sum is not finite");
    if !planes {
        assert!(run.sums.iter().skip(1).step_by(2).all(|s| *s == [0.0; 4]), "{tag}: regularisers");
    }
    check_photometric_loss(ctx, l, covered, &run, &tag);
    check_regularisers(ctx, l, labelled, planes, covered, &run, &tag);
}

/// Upload the layers, record the losses into poison-filled gradients and read them back.
fn record_losses(
    ctx: &GpuContext,
    kernels: &mut LossKernels,
    l: &Layers,
    labelled: bool,
    planes: bool,
    covered: Option<&Image<u8>>,
) -> Run {
    let pixels = u64::from(l.width * l.height);
    let up = |name: &str, data: &[[f32; 4]]| gpu::storage_init(ctx, name, data);
    let color = up("test.color", &vec4s(&[&l.color]));
    let transmission = up("test.transmission", &vec4s(&[&l.transmission, &l.alpha]));
    let reflection = up("test.reflection", &vec4s(&[&l.reflection]));
    let geometry = up("test.geometry", &vec4s(&[&l.geometry]));
    let hit = gpu::storage_init(ctx, "test.hit", &l.hit.data);
    let inputs = LossLayers {
        width: l.width,
        height: l.height,
        color: &color,
        transmission: &transmission,
        reflection: &reflection,
        geometry: &geometry,
        hit: &hit,
    };
    let target = GpuTarget::upload(
        ctx,
        "test",
        &l.target.quantised(),
        labelled.then_some(&l.annotation),
        covered,
    )
    .expect("rgb");
    let poisoned = |name: &str, bytes: u64| gpu::storage(ctx, name, bytes);
    let grads = LayerGrads {
        color: poisoned("test.g.color", pixels * 16),
        reflection: poisoned("test.g.reflection", pixels * 16),
        strength: poisoned("test.g.strength", pixels * 16),
        transmission: poisoned("test.g.transmission", pixels * 16),
        geometry: poisoned("test.g.geometry", pixels * 16),
        reflection_raw: poisoned("test.g.reflection_raw", 2 * pixels * 16),
        size: (l.width, l.height),
    };
    let settings =
        LossSettings { lambda_dssim: DSSIM_LAMBDA, regularisers: planes.then_some(WEIGHTS) };
    let mut rec = Recorder::new(ctx, "test.losses", false);
    let pending =
        kernels.record(ctx, &mut rec, &inputs, &target, &grads, &settings).expect("same size");
    rec.submit_and_wait(ctx).expect("GPU work");
    let values = pending.read(ctx).expect("readback");
    let sums: Vec<[f32; 4]> =
        gpu::read_buffer(ctx, pending.partials(), 0, pending.partial_vec4s() as usize)
            .expect("readback");
    Run { values, grads, sums }
}

/// A layer gradient of `l`'s size.
fn read_layer(ctx: &GpuContext, l: &Layers, b: &wgpu::Buffer) -> Vec<[f32; 4]> {
    gpu::read_buffer(ctx, b, 0, (l.width * l.height) as usize).expect("readback")
}

fn rgb(v: &[[f32; 4]]) -> Vec<f32> {
    v.iter().flat_map(|p| [p[0], p[1], p[2]]).collect()
}

/// `photometric_loss` against its twin: dL/dC, the loss and its parts, and the MSE.
fn check_photometric_loss(
    ctx: &GpuContext,
    l: &Layers,
    covered: Option<&Image<u8>>,
    run: &Run,
    tag: &str,
) {
    let values = &run.values;
    let twin = photometric_loss_covered(&f64s(&l.color), &f64s(&l.target), covered, DSSIM_LAMBDA)
        .expect("same size");
    let g_color = read_layer(ctx, l, &run.grads.color);
    let err = relative_error(&rgb(&g_color), &twin.grad.data);
    assert!(err < 1e-5, "{tag}: dL/dC relative error {err:e}");
    assert!(g_color.iter().all(|p| p[3] == 0.0), "{tag}: dL/dC has a fourth channel");
    for (name, got, want) in [
        ("value", values.value, twin.value),
        ("l1", values.l1, twin.l1),
        ("ssim", values.ssim, twin.ssim),
    ] {
        assert!((got - want).abs() <= 1e-5 * want.abs().max(1.0), "{tag}: {name} {got} vs {want}");
    }
    let is_covered = |i: usize| covered.is_none_or(|c| c.data[i / 3] != 0);
    let mse = l
        .color
        .data
        .iter()
        .zip(&l.target.data)
        .enumerate()
        .filter(|(i, _)| is_covered(*i))
        .map(|(_, (&a, &b))| f64::from(a - b).powi(2))
        .sum::<f64>()
        / f64::from(3 * l.width * l.height);
    assert!((values.mse - mse).abs() <= 1e-5 * mse, "{tag}: mse {} vs {mse}", values.mse);
}

/// `regularisers` against its twin, or zeros where the backward accumulates without them.
fn check_regularisers(
    ctx: &GpuContext,
    l: &Layers,
    labelled: bool,
    planes: bool,
    covered: Option<&Image<u8>>,
    run: &Run,
    tag: &str,
) {
    let g_t = read_layer(ctx, l, &run.grads.transmission);
    let g_geo = read_layer(ctx, l, &run.grads.geometry);
    let pixels = (l.width * l.height) as usize;
    let raw: Vec<[f32; 4]> =
        gpu::read_buffer(ctx, &run.grads.reflection_raw, 0, 2 * pixels).expect("readback");
    assert!(raw.iter().flatten().all(|&v| v == 0.0), "{tag}: dL/dC_raw not reset");
    if !planes {
        assert!(
            g_t.iter().chain(&g_geo).flatten().all(|&v| v == 0.0),
            "{tag}: direct grads not reset"
        );
        return;
    }
    let (ct, cr) = (f64s(&l.transmission), f64s(&l.reflection));
    let (v, m) = (f64s(&channel(&l.geometry, 1)), f64s(&channel(&l.geometry, 2)));
    let twin = regularisers(
        &RegulariserInputs {
            transmission: &ct,
            reflection: &cr,
            depth_variance: &v,
            mask: &m,
            hit: &l.hit,
            annotation: labelled.then_some(&l.annotation),
            covered,
        },
        WEIGHTS,
    );
    let err = relative_error(&rgb(&g_t), &twin.transmission.data);
    assert!(err < 1e-6, "{tag}: dL_c/dC_t relative error {err:e}");
    assert!(g_t.iter().all(|p| p[3] == 0.0), "{tag}: dL/dalpha not zero");
    let depth: Vec<f32> = g_geo.iter().map(|p| p[1]).collect();
    let mask: Vec<f32> = g_geo.iter().map(|p| p[2]).collect();
    assert!(relative_error(&depth, &twin.depth_variance.data) < 1e-6, "{tag}: dL_d/dV");
    assert!(relative_error(&mask, &twin.mask_grad.data) < 1e-6, "{tag}: dL_m/dM");
    assert!(g_geo.iter().all(|p| p[0] == 0.0 && p[3] == 0.0), "{tag}: dL/dD_t not zero");
    let values = &run.values;
    for (name, got, want) in [
        ("L_d", values.depth, twin.depth),
        ("L_c", values.conflict, twin.conflict),
        ("L_m", values.mask, twin.mask),
    ] {
        assert!((got - want).abs() <= 1e-5 * want.abs().max(1e-3), "{tag}: {name} {got} vs {want}");
    }
    // L_c is compared where it exists, not only as zero against zero.
    if l.width >= 16 && l.height >= 16 {
        assert!(twin.conflict > 0.0, "{tag}: no window counted for L_c");
    }
}

/// A context whose fresh buffers are poison-filled, so that a sum of memory no pass wrote shows.
fn poisoned_context() -> GpuContext {
    GpuContext::with_options(&DeviceOptions { poison_fresh_buffers: true, ..Default::default() })
        .expect("adapter")
}

#[test]
fn gpu_losses_match_twins() {
    let ctx = poisoned_context();
    // Both ways of covering the channels: the per-channel passes are what a frame too large for
    // the RGB scratch gets.
    for passes in [ChannelPasses::Rgb, ChannelPasses::PerChannel] {
        let mut kernels = LossKernels::with_channel_passes(&ctx, Some(passes));
        let mut rng = Rng::new(5);
        // 150x61 has 143 strips of LOSS_STRIP pixels: `loss_sums` runs more than one workgroup
        // of 64 strips, the last one partly full, and its last strip is partial too. 150 wide
        // and 141 high, the blurs take more than one workgroup of runs along x and y.
        for (w, h) in [(37, 29), (16, 16), (1, 1), (70, 3), (64, 48), (150, 61), (5, 141)] {
            let l = layers(w, h, &mut rng);
            check(&ctx, &mut kernels, &l, true, true, false);
            check(&ctx, &mut kernels, &l, false, true, false);
            check(&ctx, &mut kernels, &l, false, false, false);
            check(&ctx, &mut kernels, &l, true, true, true);
        }
    }
}

#[test]
fn frames_whose_rgb_scratch_fits_one_binding_take_the_rgb_passes() {
    let ctx = GpuContext::new().expect("adapter");
    let limit = ctx.binding_limit();
    // The RGB rows buffer (five moments of three channels, 60 bytes a pixel) is the bound.
    let fits = (limit / 60) as u32;
    assert_eq!(ChannelPasses::for_frame(&ctx, fits, 1), ChannelPasses::Rgb);
    assert_eq!(ChannelPasses::for_frame(&ctx, 640, 480), ChannelPasses::Rgb);
    assert_eq!(ChannelPasses::for_frame(&ctx, fits + 1, 1), ChannelPasses::PerChannel);
}

#[test]
fn a_loss_without_regularisers_sums_none_in_a_fresh_buffer() {
    // The regularisers' statistics are not written without planes: the strip sums must not
    // read them (poison-filled here, as a fresh buffer may hold anything), or the step's guard
    // takes the loss for not finite.
    let ctx = poisoned_context();
    let mut kernels = LossKernels::new(&ctx);
    let l = layers(37, 29, &mut Rng::new(8));
    check(&ctx, &mut kernels, &l, false, false, false);
}

#[test]
fn a_target_of_the_wrong_shape_is_refused() {
    let ctx = GpuContext::new().expect("adapter");
    let mut rng = Rng::new(6);
    let grey = random(8, 8, 1, &mut rng);
    let err = GpuTarget::upload(&ctx, "grey.png", &grey.quantised(), None, None)
        .expect_err("one channel");
    assert!(err.to_string().contains("grey.png"), "{err}");
    let rgb = random(8, 8, 3, &mut rng);
    let mask = Image::<u8>::new(8, 7, 1);
    let err = GpuTarget::upload(&ctx, "view.png", &rgb.quantised(), Some(&mask), None)
        .expect_err("mask size");
    assert!(err.to_string().contains("8x7"), "{err}");
    let err = GpuTarget::upload(&ctx, "view.png", &rgb.quantised(), None, Some(&mask))
        .expect_err("coverage");
    assert!(err.to_string().contains("coverage of view.png: 8x7"), "{err}");
}

#[test]
fn a_frame_too_large_for_one_binding_is_named_before_any_work() {
    let ctx = GpuContext::new().expect("adapter");
    let limit = ctx.binding_limit();
    // The statistics buffer (32 bytes a pixel) is the loss's largest.
    let side = ((limit / 32) as f64).sqrt().ceil() as u32 + 1;
    let err = check_frame_size(&ctx, side, side).expect_err("too large").to_string();
    assert!(err.contains(&format!("{side}x{side}")) && err.contains("statistics"), "{err}");
    assert!(err.contains("--resolution or --downscale"), "{err}");
    check_frame_size(&ctx, side / 2, side / 2).expect("a quarter of it fits");
}
