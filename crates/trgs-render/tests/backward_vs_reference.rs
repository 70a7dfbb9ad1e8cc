//! GPU adjoint stages against their CPU twins, stage by stage (`compose_bwd`:
//! compose_bwd_vs_reference.rs), on lavapipe (or whatever adapter
//! the machine has): the same forward frame and the same random upstream gradients in, gradients
//! within atol 1e-5 + rtol 1e-3 of the twin's out (plane sums relative to their scale). Each runs
//! four times (`common::contexts`): with the adapter's float atomics and subgroup reduction in
//! each replay layout (one pixel per thread as on a GPU, with and without the block walk, and a
//! tile column's rows per thread as on a CPU adapter), and with the optional features off (the
//! compare-exchange fallback without subgroups). Fresh buffers are poison-filled.
//!
//! `rasterize_bwd` is checked twice: as a stage, the twin run on the GPU's own forward results
//! (projected records, lists, pixel states, D_t) and upstream gradients, to 1e-4 of each
//! attribute's scale; and end to end, against the twin's whole f64 backward. End to end, the
//! depth-variance term w |z - D_t| has a kink where a Gaussian's depth equals the pixel's mean
//! depth D_t: there f32 and f64 pick different subgradients (sign 0 or +-1), a jump of the
//! Gaussian's weight times dL/dV. On an H100 a Gaussian 4e-7 from D_t took the other side and
//! moved its depth gradient by 1e-3 of the scale, so the end-to-end depth and mean gradients of
//! Gaussians that sit within 1e-5 of D_t at a pixel they blend are left to the stage check.
use trgs_core::Image;
use trgs_core::fixtures::{SceneSpec, random_scene};
use trgs_core::pipeline::{MIN_ALPHA, RenderSettings, TILE_SIZE, TileGrid};
use trgs_core::reference::{self, FrameGrads, PixelState, compose_bwd};
use trgs_core::scene::Gaussians;
use trgs_render::toolkit::gpu;
use trgs_render::toolkit::layout::RasterState;
use trgs_render::toolkit::{FrameStages as _, GradientStages as _};
use trgs_render::{
    BackwardOptions, Frame, GpuContext, GpuScene, Gradients, PlaneGradsRead, RenderOptions,
    Renderer, SceneGradBuffers,
};
use trgs_render::{Layer, LayerGrads};

mod common;
use common::{contexts, random_grads, spec, to_reference};

/// The acceptance rule: every value within 1e-3 of the largest |value| of its attribute (its
/// scale). Returns the attribute's relative error.
fn check_scaled(what: &str, gpu: &[f32], cpu: &[f64]) -> f64 {
    check_scaled_within(what, gpu, cpu, 1e-3, |_| false)
}

/// Every value within `tolerance` of its attribute's scale, except those `skip` names (by
/// index); the worst one is named.
fn check_scaled_within(
    what: &str,
    gpu: &[f32],
    cpu: &[f64],
    tolerance: f64,
    skip: impl Fn(usize) -> bool,
) -> f64 {
    assert_eq!(gpu.len(), cpu.len(), "{what}: value counts");
    assert!(gpu.iter().all(|v| v.is_finite()), "{what}: non-finite GPU gradient");
    let scale = cpu.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let (at, worst) = gpu
        .iter()
        .zip(cpu)
        .map(|(&g, &c)| (f64::from(g) - c).abs())
        .enumerate()
        .filter(|&(i, _)| !skip(i))
        .fold((0, 0.0f64), |m, (i, d)| if d > m.1 { (i, d) } else { m });
    let rel = if scale > 0.0 { worst / scale } else { worst };
    eprintln!(
        "{what}: scale {scale:.3e}, max |gpu - cpu| {worst:.3e} at {at} (gpu {}, cpu {}), \
         relative {rel:.2e}",
        gpu[at], cpu[at]
    );
    assert!(
        rel <= tolerance || worst <= 1e-7,
        "{what}: relative error {rel:.2e} above {tolerance:e}"
    );
    rel
}

/// The Gaussians whose depth lies within 1e-5 of the mean depth D_t of a pixel where they may
/// blend (alpha at least 0.999 of the 1/255 threshold, before the pixel's last entry): the
/// kink of |z - D_t|, where the twin and the GPU may take different subgradients.
fn on_depth_kink(frame: &reference::Frame) -> Vec<bool> {
    let pass = &frame.primary;
    let p = &pass.projected;
    let grid = TileGrid::new(frame.width(), frame.height());
    let mut kink = vec![false; p.len()];
    for y in 0..frame.height() {
        for x in 0..frame.width() {
            let tile = (y / TILE_SIZE) * grid.tiles_x + x / TILE_SIZE;
            let (start, end) = pass.ranges[tile as usize];
            let last = frame.pixels[(y * frame.width() + x) as usize].last_t as usize;
            let d = frame.depth.get(x, y, 0);
            let (px, py) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
            for &i in pass.values[start as usize..end as usize].iter().take(last) {
                let i = i as usize;
                let [a, b, c] = p.conic[i];
                let (dx, dy) = (px - p.mean2d[i].x, py - p.mean2d[i].y);
                let power = -0.5 * (a * dx * dx + c * dy * dy) - b * dx * dy;
                let near = (p.depth[i] - d).abs() <= 1e-5 * d.abs();
                if near && p.opacity[i] * power.exp() >= 0.999 * MIN_ALPHA {
                    kink[i] = true;
                }
            }
        }
    }
    kink
}

fn image_of(v: &[[f32; 4]], channels: std::ops::Range<usize>, w: u32, h: u32) -> Image<f64> {
    let mut im = Image::new(w, h, channels.len() as u32);
    im.data = v.iter().flat_map(|p| p[channels.clone()].iter().map(|&x| f64::from(x))).collect();
    im
}

fn pixel_state(s: &RasterState) -> PixelState {
    PixelState {
        t_final: f64::from(s.t_final),
        tm_final: f64::from(s.tm_final),
        last_t: s.last_t,
        last_m: s.last_m,
        weight_sum: f64::from(s.weight_sum),
        depth_sign_sum: f64::from(s.depth_sign_sum),
    }
}

/// Stage `rasterize_bwd` alone: the twin from the GPU's forward results and the upstream
/// gradients compose_bwd left in `layer_grads`, against the GPU's screen-space gradients.
fn check_rasterize_bwd_stage(
    what: &str,
    ctx: &GpuContext,
    frame: &trgs_render::Frame,
    layer_grads: &LayerGrads,
    background: [f64; 3],
    gpu_pg: &[f32],
) {
    let (w, h) = layer_grads.size;
    let n_px = (w * h) as usize;
    let n = gpu_pg.len() / 12;
    let inter =
        frame.read_intermediates(ctx, 0, n).expect("readback").expect("captured intermediates");
    let projected = to_reference(&inter.projected);
    let states: Vec<PixelState> =
        frame.read_states(ctx).expect("readback").iter().map(pixel_state).collect();
    let depth = frame.read_layer(ctx, Layer::Depth).expect("readback");
    let mut d = Image::new(w, h, 1);
    d.data = depth.data.iter().map(|&v| f64::from(v)).collect();
    let t: Vec<[f32; 4]> =
        gpu::read_buffer(ctx, &layer_grads.transmission, 0, n_px).expect("readback");
    let geo: Vec<[f32; 4]> =
        gpu::read_buffer(ctx, &layer_grads.geometry, 0, n_px).expect("readback");
    let (transmission, alpha) = (image_of(&t, 0..3, w, h), image_of(&t, 3..4, w, h));
    let (g_depth, g_v, g_m) =
        (image_of(&geo, 0..1, w, h), image_of(&geo, 1..2, w, h), image_of(&geo, 2..3, w, h));
    let twin = reference::rasterize_bwd(
        &projected,
        &inter.sorted_values,
        &inter.ranges,
        &TileGrid::new(w, h),
        &states,
        &d,
        background,
        reference::RasterizeUpstream {
            transmission: &transmission,
            depth: &g_depth,
            depth_variance: &g_v,
            mask: &g_m,
            alpha: &alpha,
        },
    );
    let twin: Vec<f64> = (0..n).flat_map(|i| projected_record(&twin, i)).collect();
    for (c, field) in PROJECTED_FIELDS.iter().enumerate() {
        let gv: Vec<f32> = gpu_pg.iter().skip(c).step_by(12).copied().collect();
        let cv: Vec<f64> = twin.iter().skip(c).step_by(12).copied().collect();
        check_scaled_within(&format!("{what} stage rasterize_bwd {field}"), &gv, &cv, 1e-4, |_| {
            false
        });
    }
}

const PROJECTED_FIELDS: [&str; 12] = [
    "dmean.x",
    "dmean.y",
    "dopacity",
    "ddepth",
    "dconic.a",
    "dconic.b",
    "dconic.c",
    "dmask",
    "dcolor.r",
    "dcolor.g",
    "dcolor.b",
    "dreflection",
];

fn flat<const N: usize>(v: &[[f32; N]]) -> Vec<f32> {
    v.iter().flatten().copied().collect()
}

fn flat64<const N: usize>(v: &[[f64; N]]) -> Vec<f64> {
    v.iter().flatten().copied().collect()
}

/// Twin screen-space gradients of the real view in the GPU record layout.
fn projected_record(pg: &reference::ProjectedGrads, i: usize) -> [f64; 12] {
    let (m, c, col) = (pg.mean2d[i], pg.conic[i], pg.color[i]);
    [
        m.x,
        m.y,
        pg.opacity[i],
        pg.depth[i],
        c[0],
        c[1],
        c[2],
        pg.mask[i],
        col[0],
        col[1],
        col[2],
        pg.reflection[i],
    ]
}

/// The whole backward against the twin's: the real view's screen-space gradients (stage
/// rasterize_bwd), then every Gaussian attribute and every plane parameter.
fn check_backward(name: &str, scene: trgs_core::fixtures::Scene, block: bool) {
    check_backward_in_pages(name, scene, block, None, false);
}

/// With `chunk`, the scene is bound `chunk` Gaussians at a time and each view's projected
/// records and gradients are held in pages of two chunks (the layout of scenes of millions).
/// With `key_pages`, the frame's key list is held in two pages, split in its middle (the
/// layout of frames of tens of millions of keys).
fn check_backward_in_pages(
    name: &str,
    mut scene: trgs_core::fixtures::Scene,
    block: bool,
    chunk: Option<u32>,
    key_pages: bool,
) {
    // Tiny and huge scales on a few Gaussians (the hard cases of the acceptance).
    let n = scene.gaussians.len();
    for i in (0..n).step_by(37) {
        scene.gaussians.log_scales[i] = [-9.0, -8.5, -9.5];
    }
    for i in (5..n).step_by(97) {
        scene.gaussians.log_scales[i] = [0.3, -0.5, 0.0];
    }
    let twin = Twin::new(name, &scene, block);
    for (mode, ctx) in contexts() {
        let what = format!("{name} ({mode})");
        let (renderer, gpu_scene, mut frame) =
            render_in_pages(&what, &ctx, &scene, &twin, chunk, key_pages);
        let layer_grads = LayerGrads::upload(&ctx, &frame, &twin.grads).expect("finite gradients");
        let bwd = BackwardOptions { block_reflection_to_gaussians: block, profile: false };
        let out = renderer.backward(&gpu_scene, &mut frame, &layer_grads, &bwd).expect("backward");
        check_screen_grads(&what, &ctx, &frame, &layer_grads, &out, &twin);
        check_gaussian_grads(&what, &ctx, &out.gaussians, &twin);
        check_plane_grads(&what, &ctx, out.planes, &twin);
    }
}

/// The twin's side of a backward check: the same forward frame and upstream gradients, and the
/// gradients they give.
struct Twin {
    /// The scene's Gaussians as the GPU holds them.
    g32: Gaussians<f32>,
    background: [f64; 3],
    /// Random upstream gradients of every layer.
    grads: FrameGrads,
    /// The whole f64 backward.
    cpu: reference::SceneGrads,
    /// The real view's screen-space gradients: the stage rasterize_bwd from compose's totals.
    cpu_pg: reference::ProjectedGrads,
    /// The Gaussians on a depth-variance kink ([`on_depth_kink`]).
    kink: Vec<bool>,
}

impl Twin {
    fn new(name: &str, scene: &trgs_core::fixtures::Scene, block: bool) -> Self {
        let n = scene.gaussians.len();
        let g32: Gaussians<f32> = scene.gaussians.cast();
        let g = g32.cast::<f64>();
        let background = [0.1, 0.2, 0.3];
        let settings = RenderSettings { background, ..Default::default() };
        let (planes, camera) = (&scene.planes, &scene.camera);
        let cpu_frame = reference::render(&g, planes, camera, &settings).expect("valid");
        let grads = random_grads(n as u64 ^ 0xbac4, &cpu_frame, planes.len());
        let options = reference::BackwardOptions { block_reflection_to_gaussians: block };
        let cpu = reference::backward(&g, planes, camera, &settings, &cpu_frame, &grads, &options)
            .expect("valid");
        // The twin's stage: pass 1's adjoint from compose's totals.
        let cg = compose_bwd(camera, planes, &cpu_frame, &grads, settings.reflection);
        let (w, h) = (cpu_frame.width(), cpu_frame.height());
        let grid = TileGrid::new(w, h);
        let pass = &cpu_frame.primary;
        let cpu_pg = reference::rasterize_bwd(
            &pass.projected,
            &pass.values,
            &pass.ranges,
            &grid,
            &cpu_frame.pixels,
            &cpu_frame.depth,
            background,
            reference::RasterizeUpstream {
                transmission: &cg.transmission,
                depth: &grads.depth,
                depth_variance: &grads.depth_variance,
                mask: &cg.mask,
                alpha: &grads.alpha,
            },
        );

        let kink = on_depth_kink(&cpu_frame);
        let kinks = kink.iter().filter(|&&k| k).count();
        eprintln!("{name}: {kinks} Gaussians on a depth-variance kink");
        assert!(kinks * 50 <= n, "{name}: {kinks} of {n} Gaussians on a kink");
        Self { g32, background, grads, cpu, cpu_pg, kink }
    }
}

/// Renders the twin's scene on `ctx` with the intermediates captured, the scene bound `chunk`
/// Gaussians at a time and the key list in two pages as asked (checked).
fn render_in_pages(
    what: &str,
    ctx: &GpuContext,
    scene: &trgs_core::fixtures::Scene,
    twin: &Twin,
    chunk: Option<u32>,
    key_pages: bool,
) -> (Renderer, GpuScene, Frame) {
    let mut renderer = Renderer::new(ctx);
    let mut gpu_scene = GpuScene::upload(ctx, &twin.g32, &scene.planes).expect("valid scene");
    if let Some(c) = chunk {
        gpu_scene.set_chunk_size(c);
        gpu_scene.set_page_len(2 * c);
    }
    let render_options = RenderOptions {
        background: twin.background.map(|v| v as f32),
        depth_variance: true,
        capture_intermediates: true,
        ..Default::default()
    };
    if key_pages {
        let whole = renderer.render(&gpu_scene, &scene.camera, &render_options).expect("render");
        renderer.set_key_page_len(whole.key_count() as u32 / 2 + 1);
    }
    let frame = renderer.render(&gpu_scene, &scene.camera, &render_options).expect("render");
    if chunk.is_some() {
        let pages: Vec<usize> = frame.views().iter().map(|v| v.projected.pages().len()).collect();
        assert!(pages.iter().all(|&p| p == 2), "{what}: pages per view {pages:?}");
    }
    if key_pages {
        let keys = frame.views()[0].keys.as_ref().map(|k| k.keys.pages().len());
        assert_eq!(keys, Some(2), "{what}: pages of the key list");
    }
    (renderer, gpu_scene, frame)
}

/// The real view's screen-space gradients: as a stage, and against the twin's stage from the
/// twin's own forward (the depth gradient of Gaussians on a kink left to the stage check).
fn check_screen_grads(
    what: &str,
    ctx: &GpuContext,
    frame: &Frame,
    layer_grads: &LayerGrads,
    out: &Gradients,
    twin: &Twin,
) {
    let n = twin.g32.len();
    let pg = out.read_projected_grads(ctx, 0).expect("readback").expect("primary view");
    let gpu_pg: Vec<f32> = pg.iter().flatten().copied().collect();
    check_rasterize_bwd_stage(what, ctx, frame, layer_grads, twin.background, &gpu_pg);
    let cpu_pg: Vec<f64> = (0..n).flat_map(|i| projected_record(&twin.cpu_pg, i)).collect();
    for (c, field) in PROJECTED_FIELDS.iter().enumerate() {
        let gv: Vec<f32> = gpu_pg.iter().skip(c).step_by(12).copied().collect();
        let cv: Vec<f64> = cpu_pg.iter().skip(c).step_by(12).copied().collect();
        let skip = |i: usize| *field == "ddepth" && twin.kink[i];
        check_scaled_within(&format!("{what} rasterize_bwd {field}"), &gv, &cv, 1e-3, skip);
    }
}

/// Every Gaussian attribute's gradient against the twin's (the means of Gaussians on a kink
/// left to the stage check).
fn check_gaussian_grads(what: &str, ctx: &GpuContext, gaussians: &SceneGradBuffers, twin: &Twin) {
    let gg = gaussians.read(ctx).expect("readback");
    let c = &twin.cpu.gaussians;
    check_scaled_within(&format!("{what} means"), &flat(&gg.means), &flat64(&c.means), 1e-3, |v| {
        twin.kink[v / 3]
    });
    check_scaled(&format!("{what} rotations"), &flat(&gg.rotations), &flat64(&c.rotations));
    check_scaled(&format!("{what} log_scales"), &flat(&gg.log_scales), &flat64(&c.log_scales));
    check_scaled(&format!("{what} opacity_logits"), &gg.opacity_logits, &c.opacity_logits);
    check_scaled(&format!("{what} sh"), &flat(&gg.sh), &flat64(&c.sh));
    check_scaled(&format!("{what} mask_logits"), &gg.mask_logits, &c.mask_logits);
    check_scaled(&format!("{what} log_reflections"), &gg.log_reflections, &c.log_reflections);
}

/// Every plane's centre, normal and R0 gradients against the twin's.
fn check_plane_grads(what: &str, ctx: &GpuContext, planes: PlaneGradsRead, twin: &Twin) {
    let planes = planes.read(ctx).expect("plane readback");
    assert_eq!(planes.len(), twin.cpu.planes.len());
    for (k, (gp, cp)) in planes.iter().zip(&twin.cpu.planes).enumerate() {
        let gv = [gp.centre.to_array(), gp.normal.to_array(), [gp.r0_logit, 0.0, 0.0]];
        let cv = [cp.centre.to_array(), cp.normal.to_array(), [cp.r0_logit, 0.0, 0.0]];
        for (part, (a, b)) in ["centre", "normal", "r0_logit"].iter().zip(gv.iter().zip(&cv)) {
            let a32: Vec<f32> = a.iter().map(|&v| v as f32).collect();
            eprintln!("{what} plane {k} {part}: gpu {a:?} cpu {b:?}");
            check_scaled(&format!("{what} plane {k} {part}"), &a32, b);
        }
    }
}

#[test]
fn backward_no_plane() {
    check_backward("no plane", random_scene(&spec(51, 600, 0, 20.0)), false);
}

#[test]
fn backward_one_plane() {
    check_backward("1 plane", random_scene(&spec(52, 600, 1, 25.0)), false);
}

#[test]
fn backward_two_planes() {
    check_backward("2 planes", random_scene(&spec(53, 600, 2, 30.0)), false);
}

#[test]
fn backward_grazing() {
    check_backward("80 deg", random_scene(&spec(54, 600, 1, 80.0)), false);
}

#[test]
fn backward_edge_on() {
    check_backward("edge-on 89.9 deg", random_scene(&spec(55, 600, 2, 89.9)), false);
}

/// The records of the Gaussians past the first page come from the second page, and their
/// gradients go to it, in every pass.
#[test]
fn backward_two_planes_in_two_pages() {
    let scene = random_scene(&spec(58, 600, 2, 30.0));
    check_backward_in_pages("2 planes, pages of 512", scene, false, Some(256), false);
}

/// The sorted key values past the key list's first page come from its second page in every
/// replay; the projected records stay in one page (the gradients' second page is then a spare
/// binding, never written).
#[test]
fn backward_two_planes_keys_in_two_pages() {
    let scene = random_scene(&spec(59, 600, 2, 30.0));
    check_backward_in_pages("2 planes, keys in two pages", scene, false, None, true);
}

#[test]
fn backward_stop_gradient() {
    check_backward("2 planes, stage-2 block", random_scene(&spec(56, 600, 2, 30.0)), true);
}

/// An image whose size is not a multiple of the tile: the last column and row of tiles are
/// partial, so some threads of the replays hold pixels outside the image (in the rows-per-thread
/// layout, a thread may hold pixels on both sides of the bottom edge).
#[test]
fn backward_partial_tiles() {
    let s = SceneSpec { width: 93, height: 70, ..spec(57, 600, 2, 35.0) };
    check_backward("93x70, 2 planes", random_scene(&s), false);
}
