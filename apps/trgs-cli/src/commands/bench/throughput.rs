//! The rasterize stage's throughput next to a trivial tiled splat loop (`shaders/bench/splat_loop.wgsl`):
//! how close pass 1 comes to the cost of blending alone.
use super::common::{median, upload};
use anyhow::{Context, Result};
use trgs_core::fixtures::RoomSpec;
use trgs_core::pipeline::TILE_SIZE;
use trgs_render::toolkit::FrameStages as _;
use trgs_render::toolkit::gpu::{self, Kernel, Recorder};
use trgs_render::toolkit::layout::{ProjectedGaussian, RasterParams};
use trgs_render::{Frame, GpuContext, RenderOptions, Renderer};

/// Pass 1's rate against the trivial loop's (evaluations a second).
pub struct Throughput {
    pub evals: u64,
    pub raster_ms: f64,
    pub ours: f64,
    pub mean_list: usize,
    pub matched: f64,
    pub long: f64,
    /// Medians over rounds of rasterize's rate / the loop's, timed in turns.
    pub matched_ratio: f64,
    pub long_ratio: f64,
    pub rounds: usize,
}

/// Pixel-Gaussian evaluations of pass 1: per pixel, the list entries visited before it stopped.
fn rasterize_evaluations(ctx: &GpuContext, frame: &Frame, gaussians: usize) -> Result<u64> {
    let states = frame.read_states(ctx)?;
    let Some(inter) = frame.read_intermediates(ctx, 0, gaussians)? else { return Ok(0) };
    let (w, h) = (frame.width(), frame.height());
    let tiles_x = w.div_ceil(TILE_SIZE);
    let mut evals = 0u64;
    for y in 0..h {
        for x in 0..w {
            let (s, e) = inter.ranges[((y / TILE_SIZE) * tiles_x + x / TILE_SIZE) as usize];
            let n = e.saturating_sub(s);
            let st = &states[(y * w + x) as usize];
            evals += u64::from(if st.last_t < n { st.last_t + 1 } else { n });
        }
    }
    Ok(evals)
}

/// The trivial tiled splat loop over `list` Gaussians of `frame`'s projection, ready to time.
struct SplatLoop {
    kernel: Kernel,
    bind: wgpu::BindGroup,
    groups: [u32; 3],
    /// Pixel-Gaussian evaluations of one dispatch.
    evals: f64,
}

impl SplatLoop {
    fn new(ctx: &GpuContext, frame: &Frame, gaussians: usize, list: usize) -> Result<Self> {
        let inter = frame.read_intermediates(ctx, 0, gaussians)?.context("frame has no views")?;
        let visible: Vec<ProjectedGaussian> =
            inter.projected.into_iter().filter(|g| g.flags & 1 != 0).take(list).collect();
        let (w, h) = (frame.width(), frame.height());
        let kernel = trgs_render::toolkit::BENCH_KERNELS.splat_loop.build(ctx);
        let projected = gpu::storage_init(ctx, "trgs.splat_loop.projected", &visible);
        let out = gpu::storage(ctx, "trgs.splat_loop.out", u64::from(w * h) * 16);
        let params = RasterParams {
            width: w,
            height: h,
            tiles_x: w.div_ceil(TILE_SIZE),
            tiles_y: h.div_ceil(TILE_SIZE),
            slot: visible.len() as u32,
            ..Default::default()
        };
        let block = gpu::params(ctx, "trgs.splat_loop.params", &params);
        let bind = kernel.bind(
            ctx,
            &[block.as_entire_binding(), projected.as_entire_binding(), out.as_entire_binding()],
        );
        let evals = f64::from(w * h) * visible.len() as f64;
        Ok(Self { kernel, bind, groups: [params.tiles_x, params.tiles_y, 1], evals })
    }

    /// GPU ms of one dispatch.
    fn time_ms(&self, ctx: &GpuContext) -> Result<f64> {
        let mut rec = Recorder::new(ctx, "trgs.splat_loop", true);
        rec.dispatch("splat_loop", &self.kernel, &self.bind, self.groups);
        rec.submit_and_wait(ctx)?;
        rec.stage_times().and_then(|t| t.first().map(|s| s.1)).context("no timestamps")
    }
}

/// Pass 1's throughput against the trivial loop's, measured in turns: each of `rounds` rounds
/// times one profiled frame and one dispatch of each loop, so that the machine's drift hits all
/// alike; the ratios are medians over rounds.
pub(super) fn measure_throughput(
    ctx: &GpuContext,
    renderer: &Renderer,
    spec: &RoomSpec,
    frame: &mut Frame,
    rounds: usize,
) -> Result<Throughput> {
    let (scene, camera) = upload(ctx, spec)?;
    let options = RenderOptions::default();
    renderer.render_into(&scene, &camera, &options, frame)?;
    let evals = rasterize_evaluations(ctx, frame, spec.gaussians)?;
    // The baseline blends as many Gaussians per tile as the frame's tiles hold on average (the
    // same batch amortisation), and also a long list of 2048.
    let tiles = spec.width.div_ceil(TILE_SIZE) * spec.height.div_ceil(TILE_SIZE);
    let mean_list = (frame.views()[0].num_keys / tiles).max(1) as usize;
    let matched = SplatLoop::new(ctx, frame, spec.gaussians, mean_list)?;
    let long = SplatLoop::new(ctx, frame, spec.gaussians, 2048)?;
    let profiled = RenderOptions { profile: true, ..options };
    let (mut ours, mut m_rates, mut l_rates, mut m_ratios, mut l_ratios) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for _ in 0..rounds {
        renderer.render_into(&scene, &camera, &profiled, frame)?;
        let ms = frame.stage_times().unwrap_or_default().iter().find(|s| s.0 == "rasterize");
        let ms = ms.map(|s| s.1).context("no rasterize timing")?;
        let rate = evals as f64 / (ms * 1e-3);
        let m = matched.evals / (matched.time_ms(ctx)? * 1e-3);
        let l = long.evals / (long.time_ms(ctx)? * 1e-3);
        ours.push(ms);
        m_rates.push(m);
        l_rates.push(l);
        m_ratios.push(rate / m);
        l_ratios.push(rate / l);
    }
    let raster_ms = median(ours);
    Ok(Throughput {
        evals,
        raster_ms,
        ours: evals as f64 / (raster_ms * 1e-3),
        mean_list,
        matched: median(m_rates),
        long: median(l_rates),
        matched_ratio: median(m_ratios),
        long_ratio: median(l_ratios),
        rounds,
    })
}

pub(super) fn print_throughput(t: &Throughput) {
    println!(
        "rasterize: {} evaluations in {:.2} ms = {:.3e}/s; trivial splat loop {:.3e}/s at {} per tile ({:.0}%), {:.3e}/s at 2048 ({:.0}%), medians over {} rounds",
        t.evals,
        t.raster_ms,
        t.ours,
        t.matched,
        t.mean_list,
        100.0 * t.matched_ratio,
        t.long,
        100.0 * t.long_ratio,
        t.rounds
    );
}
