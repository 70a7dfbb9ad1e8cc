//! Each GPU stage against its CPU twin on lavapipe (or whatever adapter the machine has), stage
//! by stage from the same inputs: the twin's binning, keys, sort and tile ranges run on the GPU's
//! projected Gaussians and must match exactly; projection, both rasterize passes and compose
//! agree within atol 1e-5 + rtol 1e-3. Fresh buffers are poison-filled. The end-to-end render is
//! compared with the reference renderer too. Every scene runs in both tile layouts (one pixel
//! per thread as on a GPU, rows per thread as on a CPU adapter).
use trgs_core::Image;
use trgs_core::fixtures::{Scene, SceneSpec, random_scene};
use trgs_core::pipeline::{ReflectionModel, RenderSettings, TileGrid, depth_key_base};
use trgs_core::reference::{
    self, Projected, ProjectionFilter, depth_key, depth_order, emit_keys, prefix_sum, rasterize,
    rasterize_reflection, sort_keys, tile_counts, tile_ranges,
};
use trgs_core::scene::Gaussians;
use trgs_render::toolkit::{FrameStages as _, ViewBuffers, ViewIntermediates};
use trgs_render::{
    BlockWidth, DeviceOptions, Frame, FrameImages, GpuContext, GpuScene, RenderOptions, Renderer,
    TileLayout,
};

mod common;
use common::{ATOL, RTOL, close, compare_values, spec, to_reference};

/// A context with `layout`, and the scan and sort block width and pass 1's walk that go with it
/// on a device of that kind (narrow blocks and the plain walk with one pixel per thread, as on a
/// GPU; wide blocks and the walk by 4 x 2 blocks with rows per thread, as on a CPU adapter, where the
/// subgroups allow it), so that both devices' kernels are checked here. The second also strides
/// its strided dispatches over three workgroups, so that each takes several blocks.
fn ctx(layout: TileLayout) -> GpuContext {
    let (width, walk, strided) = match layout {
        TileLayout::PixelPerThread => (BlockWidth::Narrow, false, None),
        TileLayout::RowsPerThread => (BlockWidth::Wide, true, Some(3)),
    };
    let opts = DeviceOptions {
        poison_fresh_buffers: true,
        tile_layout: Some(layout),
        block_width: Some(width),
        block_walk: Some(walk),
        strided_groups: strided,
        ..Default::default()
    };
    GpuContext::with_options(&opts).unwrap_or_else(|e| panic!("{e}"))
}

/// Compare images; returns the count of failing values.
fn compare(what: &str, gpu: &Image<f32>, cpu: &Image<f64>) -> usize {
    assert_eq!(
        (gpu.width, gpu.height, gpu.channels),
        (cpu.width, cpu.height, cpu.channels),
        "{what}"
    );
    compare_values(what, &gpu.data, &cpu.data, cpu.channels as usize)
}

/// How a test renders: the frame's arrays split into pages (`trgs_render::toolkit::paged`), as
/// scenes and frames beyond one binding are split, and with the depth-variance layer or not.
#[derive(Clone, Copy, Debug, Default)]
struct Split {
    /// The scene bound this many Gaussians at a time, in pages of two chunks.
    chunk: Option<u32>,
    /// The frame's key list in two pages, split in its middle.
    keys: bool,
    /// The depth-variance layer rendered (the rasterize variant training uses); without it, the
    /// variant rendering alone uses.
    depth_variance: bool,
}

const WHOLE: Split = Split { chunk: None, keys: false, depth_variance: true };
const CHUNKED: Split = Split { chunk: Some(256), keys: false, depth_variance: true };
const KEYS_PAGED: Split = Split { chunk: None, keys: true, depth_variance: true };

/// Returns how many views (the camera and the mirrored passes) the frame had.
fn check_scene(name: &str, spec: SceneSpec, split: Split) -> usize {
    check_given_scene(name, &random_scene(&spec), split)
}

fn check_given_scene(name: &str, scene: &Scene, split: Split) -> usize {
    let mut views = 0;
    for layout in [TileLayout::PixelPerThread, TileLayout::RowsPerThread] {
        views = check_scene_in(&format!("{name} ({layout:?})"), scene, split, &ctx(layout));
    }
    views
}

fn check_scene_in(name: &str, scene: &Scene, split: Split, ctx: &GpuContext) -> usize {
    let g32: Gaussians<f32> = scene.gaussians.cast();
    let g = g32.cast::<f64>();
    let options = RenderOptions {
        depth_variance: split.depth_variance,
        capture_intermediates: true,
        background: [0.1, 0.2, 0.3],
        ..Default::default()
    };
    let frame = render_split(name, scene, &g32, split, ctx, &options);
    let k = &scene.camera.intrinsics;
    let images = frame.read_images(ctx).expect("readback");
    let r = Rendered {
        ctx,
        scene,
        g: &g,
        frame: &frame,
        images: &images,
        grid: TileGrid::new(k.width, k.height),
        near: options.near,
        depth_variance: split.depth_variance,
    };
    let mut bad = 0;
    let mut all_counts = Vec::new();
    for (vi, view) in frame.views().iter().enumerate() {
        let (view_bad, counts) = check_view(&format!("{name} view {vi}"), &r, vi, view);
        bad += view_bad;
        all_counts.push(counts);
    }
    check_depth_order(name, &r, &all_counts);
    if frame.composed() {
        bad += check_compose(name, &r);
    }
    assert_eq!(bad, 0, "{name}: values outside atol {ATOL} + rtol {RTOL}");
    check_end_to_end(name, &r);
    frame.views().len()
}

/// Renders `scene` (its Gaussians `g32`) with `options`, the scene bound and the key list paged
/// as `split` says, and checks that they were.
fn render_split(
    name: &str,
    scene: &Scene,
    g32: &Gaussians<f32>,
    split: Split,
    ctx: &GpuContext,
    options: &RenderOptions,
) -> Frame {
    let mut renderer = Renderer::new(ctx);
    let mut gpu_scene = GpuScene::upload(ctx, g32, &scene.planes).expect("valid scene");
    if let Some(c) = split.chunk {
        // Pages of two chunks: with more than two chunks the rasterize passes read the
        // projected records from both of their pages.
        gpu_scene.set_chunk_size(c);
        gpu_scene.set_page_len(2 * c);
    }
    if split.keys {
        // The page boundary falls inside a sort block and, with planes, inside a view's keys.
        let whole = renderer.render(&gpu_scene, &scene.camera, options).expect("render");
        renderer.set_key_page_len(whole.key_count() as u32 / 2 + 1);
    }
    let frame = renderer.render(&gpu_scene, &scene.camera, options).expect("render");
    if let Some(c) = split.chunk {
        let want = (scene.gaussians.len() as u32).div_ceil(2 * c) as usize;
        for v in frame.views() {
            assert_eq!(v.projected.pages().len(), want, "{name}: pages of projected records");
        }
    }
    if split.keys {
        let pages = frame.views().iter().map(|v| v.keys.as_ref().map(|k| k.keys.pages().len()));
        assert!(
            pages.clone().all(|p| p == Some(2)),
            "{name}: key pages {:?}",
            pages.collect::<Vec<_>>()
        );
    }
    frame
}

/// A rendered frame and what it is checked against.
struct Rendered<'a> {
    ctx: &'a GpuContext,
    scene: &'a Scene,
    /// The scene's Gaussians as the GPU holds them (f32), in f64.
    g: &'a Gaussians<f64>,
    frame: &'a Frame,
    images: &'a FrameImages,
    grid: TileGrid,
    near: f64,
    depth_variance: bool,
}

/// View `vi` stage by stage against the twin; returns the values of its rasterize pass outside
/// the tolerance, and its tile counts.
fn check_view(what: &str, r: &Rendered, vi: usize, view: &ViewBuffers) -> (usize, Vec<u32>) {
    let n = r.g.len();
    let inter = r.frame.read_intermediates(r.ctx, vi, n).expect("readback").expect("intermediates");
    let gpu = to_reference(&inter.projected);
    check_projection(what, r, view, &gpu);
    let (counts, values, ranges) = check_lists(what, r, view, &inter, &gpu);
    let bad = check_pass(what, r, view, &gpu, &values, &ranges);
    (bad, counts)
}

/// project: against the twin in f64 from the same f32 parameters.
fn check_projection(what: &str, r: &Rendered, view: &ViewBuffers, gpu: &Projected) {
    let filter = match view.plane {
        Some(p) => ProjectionFilter::FrontOf(&r.scene.planes[p]),
        None => ProjectionFilter::All,
    };
    let k = &r.scene.camera.intrinsics;
    let cpu = reference::project(r.g, &view.view, k, filter, &view.limit, 0.2);
    let mut proj_bad = 0;
    for i in 0..r.g.len() {
        if cpu.visible[i] != gpu.visible[i] {
            eprintln!("{what}: Gaussian {i} visible cpu {} gpu {}", cpu.visible[i], gpu.visible[i]);
            proj_bad += 1;
            continue;
        }
        if !cpu.visible[i] {
            continue;
        }
        let pairs = [
            (gpu.mean2d[i].x, cpu.mean2d[i].x),
            (gpu.mean2d[i].y, cpu.mean2d[i].y),
            (gpu.depth[i], cpu.depth[i]),
            (gpu.extent[i].x, cpu.extent[i].x),
            (gpu.extent[i].y, cpu.extent[i].y),
            (gpu.color[i][0], cpu.color[i][0]),
            (gpu.color[i][1], cpu.color[i][1]),
            (gpu.color[i][2], cpu.color[i][2]),
            (gpu.opacity[i], cpu.opacity[i]),
            (gpu.mask[i], cpu.mask[i]),
            (gpu.reflection[i], cpu.reflection[i]),
        ];
        // The conic is compared relative to its largest entry (b can be near zero).
        let scale = cpu.conic[i].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let conic_ok =
            (0..3).all(|c| (gpu.conic[i][c] - cpu.conic[i][c]).abs() <= ATOL + RTOL * scale);
        if !pairs.iter().all(|&(a, b)| close(a, b)) || !conic_ok || gpu.glass[i] != cpu.glass[i] {
            eprintln!("{what}: Gaussian {i} projected differently: {pairs:?}");
            proj_bad += 1;
        }
    }
    assert_eq!(proj_bad, 0, "{what}: project");
}

/// Binning, depth order, scan, keys, sort, ranges: exact, from the GPU's projected values.
/// Returns the view's tile counts, and its sorted values and tile ranges.
fn check_lists(
    what: &str,
    r: &Rendered,
    view: &ViewBuffers,
    inter: &ViewIntermediates,
    gpu: &Projected,
) -> (Vec<u32>, Vec<u32>, Vec<(u32, u32)>) {
    let grid = &r.grid;
    let counts = tile_counts(gpu, grid, &view.limit);
    assert_eq!(inter.counts, counts, "{what}: tile_counts");
    let order = depth_order(gpu, &counts, r.near);
    assert_eq!(inter.order, order, "{what}: depth_order");
    let ordered: Vec<u32> = order.iter().map(|&i| counts[i as usize]).collect();
    let (offsets, total) = prefix_sum(&ordered);
    assert_eq!(view.num_keys, total, "{what}: key total");
    let (mut keys, mut values) = emit_keys(gpu, grid, &view.limit, &order, &offsets, total);
    let (ek, ev) = inter.emitted.as_ref().expect("captured");
    assert_eq!((ek, ev), (&keys, &values), "{what}: emit_keys");
    sort_keys(&mut keys, &mut values);
    assert_eq!(inter.sorted_keys, keys, "{what}: sort keys");
    assert_eq!(inter.sorted_values, values, "{what}: sort values");
    let ranges = tile_ranges(&keys, grid.tile_count());
    assert_eq!(inter.ranges, ranges, "{what}: tile_ranges");
    eprintln!("{what}: {} visible, {total} keys", gpu.visible.iter().filter(|&&v| v).count());
    (counts, values, ranges)
}

/// The view's rasterize pass from the GPU's sorted lists; returns the values outside the
/// tolerance.
fn check_pass(
    what: &str,
    r: &Rendered,
    view: &ViewBuffers,
    gpu: &Projected,
    values: &[u32],
    ranges: &[(u32, u32)],
) -> usize {
    let (images, grid) = (r.images, &r.grid);
    let mut bad = 0;
    match view.plane {
        None => {
            let out = rasterize(gpu, values, ranges, grid, [0.1, 0.2, 0.3]);
            bad += compare(&format!("{what} C_t"), &images.transmission, &out.transmission);
            bad += compare(&format!("{what} D_t"), &images.depth, &out.depth);
            if r.depth_variance {
                bad += compare(&format!("{what} V"), &images.depth_variance, &out.depth_variance);
            }
            bad += compare(&format!("{what} M"), &images.mask, &out.mask);
            bad += compare(&format!("{what} alpha"), &images.alpha, &out.alpha);
            let states = r.frame.read_states(r.ctx).expect("readback");
            let stops = states
                .iter()
                .zip(&out.pixels)
                .filter(|(g, c)| g.last_t != c.last_t || g.last_m != c.last_m)
                .count();
            assert_eq!(stops, 0, "{what}: stop points");
        }
        Some(p) => {
            let (camera, plane) = (&r.scene.camera, &r.scene.planes[p]);
            let out = rasterize_reflection(gpu, values, ranges, grid, &view.limit, camera, plane);
            let pi = images.planes[p].as_ref().expect("plane pass ran");
            assert_eq!(pi.footprint, view.limit);
            bad += compare(&format!("{what} C_raw"), &pi.raw_color, &out.raw_color);
            bad += compare(&format!("{what} A"), &pi.intensity, &out.intensity);
        }
    }
    bad
}

/// The depth order of all views together (whose tile counts are `all_counts`), and the scan of
/// its counts: exact.
fn check_depth_order(name: &str, r: &Rendered, all_counts: &[Vec<u32>]) {
    let (ctx, frame, n) = (r.ctx, r.frame, r.g.len());
    let depth = frame.read_depth_order(ctx).expect("readback").expect("depth order");
    let base = depth_key_base(r.near);
    let mut expected: Vec<(u32, u32, u32)> = Vec::new();
    for (vi, counts) in all_counts.iter().enumerate() {
        let projected = frame.read_projected(ctx, vi).expect("readback").expect("projected");
        for (i, &c) in counts.iter().enumerate() {
            if c > 0 {
                let entry = (vi * n + i) as u32;
                expected.push((depth_key(projected[i].color[3], base), entry, c));
            }
        }
    }
    expected.sort_unstable();
    let entries: Vec<u32> = expected.iter().map(|e| e.1).collect();
    let depths: Vec<u32> = expected.iter().map(|e| e.0).collect();
    assert_eq!(depth.entries, entries, "{name}: depth_order entries");
    assert_eq!(depth.depths, depths, "{name}: depth_order depths");
    let (offsets, total) = prefix_sum(&expected.iter().map(|e| e.2).collect::<Vec<_>>());
    assert_eq!(depth.offsets, offsets, "{name}: prefix_sum of the ordered counts");
    assert_eq!(depth.total, total, "{name}: key total");
}

/// Compose from the GPU's own pass outputs; returns the values outside the tolerance.
fn check_compose(name: &str, r: &Rendered) -> usize {
    let images = r.images;
    let f64img = |i: &Image<f32>| i.map(f64::from);
    let raw: Vec<Option<Image<f64>>> =
        images.planes.iter().map(|p| p.as_ref().map(|p| f64img(&p.raw_color))).collect();
    let int: Vec<Option<Image<f64>>> =
        images.planes.iter().map(|p| p.as_ref().map(|p| f64img(&p.intensity))).collect();
    let raw_refs: Vec<Option<&Image<f64>>> = raw.iter().map(Option::as_ref).collect();
    let int_refs: Vec<Option<&Image<f64>>> = int.iter().map(Option::as_ref).collect();
    let out = reference::compose(
        &r.scene.camera,
        &r.scene.planes,
        &f64img(&images.transmission),
        &f64img(&images.mask),
        &raw_refs,
        &int_refs,
        ReflectionModel::default(),
    );
    let hit_diff = images.hit.data.iter().zip(&out.hit.data).filter(|(a, b)| a != b).count();
    eprintln!("{name}: compose hit mask differs at {hit_diff} pixels");
    assert!(hit_diff <= 2, "{name}: hit mask differs at {hit_diff} pixels");
    let mut bad = 0;
    if hit_diff == 0 {
        bad += compare(&format!("{name} C"), &images.color, &out.color);
        bad += compare(&format!("{name} C_r"), &images.reflection, &out.reflection);
        bad += compare(&format!("{name} R_raw"), &images.strength_raw, &out.strength_raw);
        bad += compare(&format!("{name} R"), &images.strength, &out.strength);
    }
    bad
}

/// End to end against the reference renderer.
fn check_end_to_end(name: &str, r: &Rendered) {
    let settings = RenderSettings { near: 0.2, background: [0.1, 0.2, 0.3], ..Default::default() };
    let (scene, images) = (r.scene, r.images);
    let cpu = reference::render(r.g, &scene.planes, &scene.camera, &settings).expect("reference");
    let total = compare(&format!("{name} end-to-end C"), &images.color, &cpu.color);
    assert!(
        total as f64 <= 1e-3 * cpu.color.data.len() as f64,
        "{name}: end-to-end C differs beyond tolerance at {total} values"
    );
}

#[test]
fn no_plane_matches_reference() {
    check_scene("no plane", spec(101, 1500, 0, 20.0), WHOLE);
}

#[test]
fn without_depth_variance_matches_reference() {
    // The rasterize variants a render without training takes: whole, and in pages.
    let plain = Split { depth_variance: false, ..WHOLE };
    check_scene("no depth variance", spec(111, 1500, 1, 25.0), plain);
    check_scene(
        "no depth variance, chunked",
        spec(112, 700, 2, 30.0),
        Split { depth_variance: false, ..CHUNKED },
    );
}

#[test]
fn one_plane_matches_reference() {
    check_scene("one plane", spec(102, 1500, 1, 25.0), WHOLE);
}

#[test]
fn two_planes_match_reference() {
    check_scene("two planes", spec(103, 1500, 2, 30.0), WHOLE);
}

#[test]
fn four_planes_match_reference() {
    // Five views: the cheap culls run in two dispatches (CULL_VIEWS views each), the second
    // with an unused view slot.
    let views = check_scene("four planes", spec(109, 1500, 4, 30.0), WHOLE);
    assert_eq!(views, 5, "every plane's mirrored pass ran");
}

#[test]
fn chunked_four_planes_match_reference() {
    // Several chunks and several cull groups: each (chunk, group) dispatch and its work records.
    let views = check_scene("chunked four planes", spec(110, 700, 4, 30.0), CHUNKED);
    assert_eq!(views, 5, "every plane's mirrored pass ran");
}

/// The key list in two pages: emit_keys writes, the sort reads and scatters, tile_ranges and
/// both rasterize passes read across the page boundary, with the projected records in one page
/// (the paged rasterize kernels then bind its first page twice).
#[test]
fn key_list_in_two_pages_matches_reference() {
    let views = check_scene("keys in two pages", spec(112, 1500, 2, 30.0), KEYS_PAGED);
    assert_eq!(views, 3, "both planes' mirrored passes ran");
}

/// Both the projected records and the keys in two pages.
#[test]
fn chunked_key_list_in_two_pages_matches_reference() {
    let split = Split { keys: true, ..CHUNKED };
    check_scene("chunked, keys in two pages", spec(113, 700, 2, 30.0), split);
}

#[test]
fn plane_filling_the_image_matches_reference() {
    // A pane far larger than the view: its footprint is the whole image, so compose covers it
    // and the renderer skips the copy and clears of the pixels outside the footprints.
    let mut scene = random_scene(&spec(111, 1500, 1, 20.0));
    scene.planes[0].width = 200.0;
    scene.planes[0].height = 200.0;
    let views = check_given_scene("plane filling the image", &scene, WHOLE);
    assert_eq!(views, 2, "the plane's mirrored pass ran");
}

#[test]
fn grazing_view_matches_reference() {
    check_scene("grazing 80 deg", spec(104, 1200, 1, 80.0), WHOLE);
}

#[test]
fn plane_seen_edge_on_matches_reference() {
    check_scene("edge-on 89.9 deg", spec(105, 1200, 2, 89.9), WHOLE);
}

#[test]
fn chunked_bindings_match_reference() {
    // 700 Gaussians bound 256 at a time: the split that scenes above the binding limit use.
    check_scene("chunked", spec(106, 700, 1, 40.0), CHUNKED);
}

#[test]
fn many_gaussians_match_reference() {
    // Enough Gaussians that the depth order (19716 entries over three views) spans several sort
    // blocks (4096 entries each, 16384 with wide blocks) with its count known on the GPU only,
    // the key list several blocks of every pass, and the scans two levels (1024 and 4096 values
    // a block).
    check_scene("many", spec(107, 12_000, 2, 30.0), WHOLE);
}

#[test]
fn partial_tiles_match_reference() {
    // 93x70: the last column and row of tiles are partial, and in the rows-per-thread layout a
    // thread holds pixels on both sides of the bottom edge.
    check_scene("93x70", SceneSpec { width: 93, height: 70, ..spec(108, 1500, 2, 35.0) }, WHOLE);
}

#[test]
fn profiled_frame_times_each_kernel_within_its_stage() {
    let ctx = ctx(TileLayout::RowsPerThread);
    if !ctx.capabilities.timestamps {
        eprintln!("no timestamp queries on this adapter: nothing to time");
        return;
    }
    let scene = random_scene(&spec(110, 1500, 1, 25.0));
    let g32: Gaussians<f32> = scene.gaussians.cast();
    let gpu_scene = GpuScene::upload(&ctx, &g32, &scene.planes).expect("valid scene");
    let renderer = Renderer::new(&ctx);
    let plain = renderer.render(&gpu_scene, &scene.camera, &RenderOptions::default());
    let options = RenderOptions { profile: true, ..Default::default() };
    let profiled = renderer.render(&gpu_scene, &scene.camera, &options).expect("render");
    // Timing changes nothing drawn.
    let (a, b) = (plain.expect("render").read_images(&ctx), profiled.read_images(&ctx));
    assert_eq!(a.expect("readback").color.data, b.expect("readback").color.data);
    let stages: Vec<&str> = profiled.stage_times().expect("profiled").iter().map(|s| s.0).collect();
    let kernels = profiled.kernel_times().expect("profiled");
    let find = |stage: &str, kernel: &str| {
        kernels.iter().find(|k| k.stage == stage && k.kernel == kernel).map(|k| k.dispatches)
    };
    // Every dispatch is timed under the stage it serves: the depth order's scan of its presence
    // bits, five radix passes of count, histogram scan and scatter, and its counts; the key
    // sort's passes and their scans under `sort`; `prefix_sum` is the scan of the tile counts.
    let passes =
        trgs_core::pipeline::DEPTH_KEY_BITS.div_ceil(trgs_render::toolkit::layout::SORT_RADIX_BITS);
    assert_eq!(find("depth_order", "prefix_sum_bits"), Some(1));
    assert_eq!(find("depth_order", "depth_order_compact"), Some(1));
    assert_eq!(find("depth_order", "sort_count"), Some(passes));
    assert!(find("depth_order", "prefix_sum") >= Some(passes), "the histograms' scans");
    assert_eq!(find("depth_order", "sort_scatter"), Some(passes));
    assert_eq!(find("depth_order", "depth_order_counts"), Some(1));
    assert!(find("sort", "prefix_sum").is_some(), "the key sort's histogram scans");
    assert!(find("prefix_sum", "prefix_sum").is_some(), "the scan of the tile counts");
    let order = ["project", "tile_counts", "depth_order", "prefix_sum", "emit_keys", "sort"];
    assert_eq!(stages[..order.len()], order, "stages in the order they first ran");
    assert_eq!(find("rasterize_reflection", "rasterize_reflection"), Some(1));
}
