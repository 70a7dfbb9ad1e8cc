//! Key lists sized from earlier frames (`KeySizing::FromEarlierFrames`): the render does not wait
//! for its binning's totals, emit_keys drops what the list cannot hold, and the frame says
//! afterwards whether it held every key. A frame whose list held its keys must be the frame an
//! exact list gives, bit for bit; one that outgrew its list must say so, stay finite, and size
//! the next render so that it fits.
use trgs_core::fixtures::{Scene, random_scene};
use trgs_core::scene::Gaussians;
use trgs_render::toolkit::FrameStages as _;
use trgs_render::toolkit::gpu::read_buffer;
use trgs_render::{
    Frame, GpuContext, GpuScene, KeySizing, KeyTotals, Layer, RenderError, RenderOptions, Renderer,
};

mod common;
use common::spec;

/// A context whose strided dispatches (emit_keys, tile_ranges) have three workgroups, so that
/// each takes several blocks, below the count on the GPU and past it.
fn ctx() -> GpuContext {
    let opts = trgs_render::DeviceOptions {
        poison_fresh_buffers: true,
        strided_groups: Some(3),
        ..Default::default()
    };
    GpuContext::with_options(&opts).unwrap_or_else(|e| panic!("{e}"))
}

fn upload(ctx: &GpuContext, scene: &Scene) -> GpuScene {
    let g: Gaussians<f32> = scene.gaussians.cast();
    GpuScene::upload(ctx, &g, &scene.planes).expect("valid scene")
}

fn options(key_sizing: KeySizing) -> RenderOptions {
    RenderOptions {
        depth_variance: true,
        background: [0.1, 0.2, 0.3],
        key_sizing,
        ..Default::default()
    }
}

/// Every layer of `frame`, in Layer::ALL order.
fn layers(ctx: &GpuContext, frame: &Frame) -> Vec<Vec<f32>> {
    Layer::ALL.iter().map(|&l| frame.read_layer(ctx, l).expect("readback").data).collect()
}

/// A scene, and the same camera over a fifth of its Gaussians: far fewer keys, so that a list
/// sized from the small one's frame cannot hold the big one's.
fn big_and_small() -> (Scene, Scene) {
    let big = random_scene(&spec(133, 4000, 1, 30.0));
    let mut small = big.clone();
    let n = big.gaussians.len() / 5;
    small.gaussians = big.gaussians.subset(|i| i < n);
    (big, small)
}

/// Renders `scene` with an exact list into a fresh frame: its layers and key total.
fn exact(renderer: &Renderer, scene: &GpuScene, camera: &Scene) -> (Vec<Vec<f32>>, u64) {
    let ctx = renderer.context();
    let mut frame = Frame::default();
    let o = options(KeySizing::Exact);
    renderer.render_into(scene, &camera.camera, &o, &mut frame).expect("render");
    let totals = frame.settle_keys(ctx).expect("totals").expect("rendered");
    assert!(totals.held());
    (layers(ctx, &frame), totals.keys)
}

/// A frame that has held `scene`'s keys once, then renders it sized from that frame.
fn check_same_frame(renderer: &Renderer, scene: &Scene, what: &str) {
    let ctx = renderer.context();
    let gpu = upload(ctx, scene);
    let (want, keys) = exact(renderer, &gpu, scene);
    assert!(keys > 1000, "{what}: {keys} keys");
    let mut frame = Frame::default();
    let o = options(KeySizing::FromEarlierFrames);
    // The first render into a frame has nothing to size from: exact.
    renderer.render_into(&gpu, &scene.camera, &o, &mut frame).expect("render");
    let first = frame.settle_keys(ctx).expect("totals").expect("rendered");
    assert_eq!(first, KeyTotals { keys, capacity: keys }, "{what}: first render");
    renderer.render_into(&gpu, &scene.camera, &o, &mut frame).expect("render");
    let second = frame.settle_keys(ctx).expect("totals").expect("rendered");
    assert_eq!(second, KeyTotals { keys, capacity: keys + keys / 4 }, "{what}: second render");
    assert_eq!(frame.key_count(), keys, "{what}: the views' keys, once settled");
    let pages: Vec<_> =
        frame.views().iter().map(|v| v.keys.as_ref().map(|k| k.keys.pages().len())).collect();
    let paged = keys > u64::from(renderer.key_page_len());
    assert!(
        pages.iter().all(|&p| p == Some(1 + usize::from(paged))),
        "{what}: key pages {pages:?}"
    );
    let got = layers(ctx, &frame);
    for (layer, (g, w)) in Layer::ALL.iter().zip(got.iter().zip(&want)) {
        let differ = g.iter().zip(w).filter(|(a, b)| a.to_bits() != b.to_bits()).count();
        assert_eq!(differ, 0, "{what}: {layer:?} differs from the exact list's in {differ} values");
    }
}

#[test]
fn a_list_sized_from_an_earlier_frame_renders_as_the_exact_list() {
    let renderer = Renderer::new(&ctx());
    check_same_frame(&renderer, &random_scene(&spec(131, 3000, 2, 30.0)), "two planes");
}

#[test]
fn a_list_sized_from_an_earlier_frame_in_two_pages_renders_as_the_exact_list() {
    let ctx = ctx();
    let scene = random_scene(&spec(132, 3000, 2, 30.0));
    let mut renderer = Renderer::new(&ctx);
    let (_, keys) = exact(&renderer, &upload(&ctx, &scene), &scene);
    // The exact list and the larger one sized from it both split in two pages (which hold the
    // larger one whole).
    renderer.set_key_page_len((keys + keys / 4) as u32 / 2 + 1);
    check_same_frame(&renderer, &scene, "keys in two pages");
}

#[test]
fn a_frame_that_outgrows_its_list_says_so_and_sizes_the_next() {
    let ctx = ctx();
    let renderer = Renderer::new(&ctx);
    let (big, small) = big_and_small();
    let (big_gpu, small_gpu) = (upload(&ctx, &big), upload(&ctx, &small));
    let (want, keys) = exact(&renderer, &big_gpu, &big);
    let (_, few) = exact(&renderer, &small_gpu, &small);
    assert!(few + few / 4 < keys, "{few} keys, then {keys}");

    let o = options(KeySizing::FromEarlierFrames);
    let mut frame = Frame::default();
    renderer.render_into(&small_gpu, &small.camera, &o, &mut frame).expect("render");
    renderer.render_into(&big_gpu, &big.camera, &o, &mut frame).expect("render");
    let outgrown = frame.settle_keys(&ctx).expect("totals").expect("rendered");
    assert_eq!(outgrown, KeyTotals { keys, capacity: few + few / 4 });
    assert!(!outgrown.held());
    // The list holds its capacity's first keys, which the tile ranges and the rasterize
    // passes cover, and nothing past it.
    let v = &frame.views()[0];
    let ranges = v.ranges.as_ref().expect("ranges");
    let ranges: Vec<[u32; 2]> =
        read_buffer(&ctx, ranges, 0, (ranges.size() / 8) as usize).expect("readback");
    let end = ranges.iter().map(|r| u64::from(r[1])).max().unwrap_or(0);
    assert_eq!(end, outgrown.capacity, "the sorted keys the tile ranges cover");
    // Keys were dropped, not written out of bounds: every layer stays finite.
    for (layer, values) in Layer::ALL.iter().zip(layers(&ctx, &frame)) {
        assert!(values.iter().all(|v| v.is_finite()), "{layer:?} of the outgrown frame");
    }
    // The next render is sized from the outgrown frame's total, and holds it.
    renderer.render_into(&big_gpu, &big.camera, &o, &mut frame).expect("render");
    let next = frame.settle_keys(&ctx).expect("totals").expect("rendered");
    assert_eq!(next, KeyTotals { keys, capacity: keys + keys / 4 });
    assert_eq!(layers(&ctx, &frame), want, "the frame rendered again");
}

#[test]
fn a_finished_render_that_outgrew_its_list_is_rendered_again_exactly() {
    // `render_finished`, how the viewer draws and `render_fps` times: one wait a frame (the
    // finishing pass's), and a frame that outgrew its list rendered again before it is used.
    let ctx = ctx();
    let renderer = Renderer::new(&ctx);
    let (big, small) = big_and_small();
    let (big_gpu, small_gpu) = (upload(&ctx, &big), upload(&ctx, &small));
    let (want, _) = exact(&renderer, &big_gpu, &big);
    // `options` asks for exact lists: `render_finished` sizes from earlier frames regardless.
    let o = options(KeySizing::Exact);
    let mut frame = Frame::default();
    let mut finished = Vec::new();
    let mut times_finished = Vec::new();
    for (scene, camera) in [(&small_gpu, &small.camera), (&big_gpu, &big.camera)] {
        finished.clear();
        let finish = |f: &Frame| -> Result<(), RenderError> {
            finished.push(layers(&ctx, f));
            Ok(())
        };
        renderer.render_finished(scene, camera, &o, &mut frame, finish).expect("render");
        times_finished.push(finished.len());
    }
    // The first render into the frame is exact and finished once; the second outgrows its
    // list, is finished, then rendered again: what was finished last is the exact frame.
    assert_eq!(times_finished, [1, 2], "times each render was finished");
    assert!(finished[1] == want, "the frame rendered again is not the exact frame");
    // Once more, the list now holds the frame: one wait, the finishing pass's.
    let waits = ctx.waits();
    let wait = |_: &Frame| -> Result<(), RenderError> {
        Ok(trgs_render::toolkit::gpu::wait_for_gpu(&ctx, "the finishing pass")?)
    };
    renderer.render_finished(&big_gpu, &big.camera, &o, &mut frame, wait).expect("render");
    assert_eq!(ctx.waits() - waits, 1, "a render in steady state waits once");
}
