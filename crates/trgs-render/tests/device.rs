//! The device layer on whatever adapter the machine has (lavapipe in CI): a device is created, a
//! compute kernel runs and its result reads back, with and without the optional features.
use trgs_render::{BlockWidth, DeviceOptions, GpuContext, TileLayout};

const KERNEL: &str = r"
@group(0) @binding(0) var<storage, read_write> out: array<f32>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < arrayLength(&out) {
        out[id.x] = f32(id.x) * 0.5 + 1.0;
    }
}
";

fn run_kernel(ctx: &GpuContext, n: u32) -> Vec<f32> {
    let d = &ctx.device;
    let size = u64::from(n) * 4;
    let buf = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("trgs.test.out"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let read = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("trgs.test.readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("trgs.test.kernel"),
        source: wgpu::ShaderSource::Wgsl(KERNEL.into()),
    });
    let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("trgs.test.pipeline"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let bind = d.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("trgs.test.bind"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry { binding: 0, resource: buf.as_entire_binding() }],
    });
    let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("trgs.test.encoder"),
    });
    {
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("trgs.test.pass"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(n.div_ceil(64), 1, 1);
    }
    enc.copy_buffer_to_buffer(&buf, 0, &read, 0, size);
    ctx.queue.submit([enc.finish()]);
    let slice = read.slice(..);
    slice.map_async(wgpu::MapMode::Read, |r| r.expect("map readback buffer"));
    d.poll(wgpu::PollType::wait_indefinitely()).expect("device poll");
    let bytes = slice.get_mapped_range().expect("mapped range");
    bytes.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect()
}

#[test]
fn compute_kernel_runs_and_reads_back() {
    for disable in [false, true] {
        let opts = DeviceOptions { disable_optional_features: disable, ..Default::default() };
        let ctx = GpuContext::with_options(&opts).unwrap_or_else(|e| panic!("{e}"));
        println!("{}", ctx.describe());
        let c = ctx.capabilities;
        if disable {
            assert!(!c.float_atomics && !c.subgroups && !c.timestamps, "{c:?}");
        }
        // The layout follows the adapter, whatever its features.
        assert_eq!(c.tile_layout, TileLayout::for_adapter(ctx.info.device_type));
        assert_eq!(c.block_width, BlockWidth::for_adapter(ctx.info.device_type));
        // The walk by pixel blocks needs subgroups that fit in a block (at most 8 lanes).
        let small = ctx.info.subgroup_max_size > 0 && ctx.info.subgroup_max_size <= 8;
        assert_eq!(c.block_walk, c.subgroups && small, "{c:?}, {:?}", ctx.info);
        let out = run_kernel(&ctx, 1000);
        assert!(out.iter().enumerate().all(|(i, &v)| v == i as f32 * 0.5 + 1.0));
    }
}

#[test]
fn block_walk_is_off_without_subgroups_even_when_asked_for() {
    let opts = DeviceOptions {
        disable_optional_features: true,
        block_walk: Some(true),
        ..Default::default()
    };
    let ctx = GpuContext::with_options(&opts).unwrap_or_else(|e| panic!("{e}"));
    assert!(!ctx.capabilities.block_walk, "{:?}", ctx.capabilities);
}

#[test]
fn unknown_adapter_name_is_a_clear_error() {
    let opts = DeviceOptions { adapter_name: Some("no-such-gpu-xyz".into()), ..Default::default() };
    let err = GpuContext::with_options(&opts).expect_err("must fail");
    let msg = err.to_string();
    assert!(msg.contains("no-such-gpu-xyz") || msg.contains("no GPU adapter"), "{msg}");
}

#[test]
fn a_device_with_webgpu_default_limits_is_refused_by_name() {
    let ctx = GpuContext::new().unwrap_or_else(|e| panic!("{e}"));
    // What a UI toolkit creates when it asks for nothing: 8 storage buffers per stage.
    let descriptor = wgpu::DeviceDescriptor {
        label: Some("trgs.test.default_limits"),
        required_limits: wgpu::Limits::default(),
        ..Default::default()
    };
    let (device, queue) =
        pollster::block_on(ctx.adapter.request_device(&descriptor)).expect("default device");
    let err =
        GpuContext::from_device(ctx.adapter.clone(), device, queue, &DeviceOptions::default())
            .expect_err("8 storage buffers are too few");
    let text = err.to_string();
    assert!(text.contains("storage buffers") && text.contains("device_descriptor"), "{text}");
}

#[test]
fn spread_block_in_wgsl_matches_its_twin_on_every_grid_shape() {
    // The spread changes which workgroup takes which block, so the stage tests pass with any
    // bijection: this checks the WGSL itself, including the rows of split dispatches (more than
    // 65,535 workgroups), which no stage test reaches.
    use trgs_render::toolkit::gpu::{self, Recorder, grid_1d, spread_block, spread_step};
    use trgs_render::toolkit::layout::ScanParams;
    let ctx = GpuContext::new().expect("adapter");
    let kernel = trgs_render::toolkit::BENCH_KERNELS.spread_block_check.build(&ctx);
    let shapes = [grid_1d(13), grid_1d(3000), [7, 3, 1], [4, 40, 1], [65_535, 3, 1]];
    for groups in shapes {
        let n = groups[0] * groups[1];
        let spread = spread_step(groups);
        assert_ne!(spread, 0, "{groups:?}: a shape that spreads");
        let params = gpu::params(&ctx, "test.params", &ScanParams { spread, ..Default::default() });
        let out = gpu::storage(&ctx, "test.blocks", u64::from(n) * 4);
        let bind = kernel.bind(&ctx, &[params.as_entire_binding(), out.as_entire_binding()]);
        let mut rec = Recorder::new(&ctx, "test.spread", false);
        rec.dispatch("spread_block_check", &kernel, &bind, groups);
        rec.submit_and_wait(&ctx).expect("GPU work");
        let got: Vec<u32> = gpu::read_buffer(&ctx, &out, 0, n as usize).expect("readback");
        let want: Vec<u32> = (0..groups[1])
            .flat_map(|y| (0..groups[0]).map(move |x| [x, y]))
            .map(|wid| spread_block(wid, groups, spread))
            .collect();
        assert!(got == want, "{groups:?}: the WGSL and its twin take different blocks");
    }
}

#[test]
fn draw_below_in_wgsl_matches_its_twin_bit_for_bit() {
    // MCMC relocation draws Gaussians by these integers; WGSL builds their 64-bit product from
    // 16-bit halves. Totals at the edges of the halves and of u32, and random ones.
    use trgs_core::reference::{draw_below, pcg_hash};
    use trgs_render::toolkit::gpu::{self, Recorder, grid_1d};
    let ctx = GpuContext::new().expect("adapter");
    let kernel = trgs_render::toolkit::BENCH_KERNELS.draw_below_check.build(&ctx);
    let edges = [1, 2, 3, 0xffff, 0x1_0000, 0x1_0001, 0x7fff_ffff, 0x8000_0000, u32::MAX - 1];
    let n = 4096u32;
    let totals: Vec<u32> = (0..n)
        .map(|j| edges.get(j as usize).copied().unwrap_or(pcg_hash(j.wrapping_mul(31)) | 1))
        .chain([u32::MAX])
        .collect();
    let seeds: Vec<u32> = (0..=n).map(|j| pcg_hash(j ^ 0x5eed)).collect();
    let count = totals.len();
    let draws = gpu::storage(&ctx, "test.draws", count as u64 * 4);
    let seeds_buf = gpu::storage_init(&ctx, "test.seeds", &seeds);
    let totals_buf = gpu::storage_init(&ctx, "test.totals", &totals);
    let bind = kernel.bind(
        &ctx,
        &[
            seeds_buf.as_entire_binding(),
            totals_buf.as_entire_binding(),
            gpu::range(&draws, 0, count as u64 * 4),
        ],
    );
    let mut rec = Recorder::new(&ctx, "test.draw_below", false);
    rec.dispatch("draw_below_check", &kernel, &bind, grid_1d((count as u32).div_ceil(64)));
    rec.submit_and_wait(&ctx).expect("GPU work");
    let got: Vec<u32> = gpu::read_buffer(&ctx, &draws, 0, count).expect("readback");
    let want: Vec<u32> = (0..count).map(|j| draw_below(seeds[j], j as u32, totals[j])).collect();
    for j in 0..count {
        assert_eq!(got[j], want[j], "draw {j}: seed {:#x}, total {:#x}", seeds[j], totals[j]);
        assert!(got[j] < totals[j], "draw {j} is not below its total");
    }
    // The cases reach the partial products' carry: the high words of a and b times the total
    // alone are wrong for most of them.
    let no_carry = (0..count)
        .filter(|&j| {
            let (a, b) = (pcg_hash(j as u32 ^ pcg_hash(seeds[j])), totals[j]);
            let (a0, a1, b0, b1) = (a & 0xffff, a >> 16, b & 0xffff, b >> 16);
            a1 * b1 + ((a1 * b0) >> 16) + ((a0 * b1) >> 16) != want[j]
        })
        .count();
    assert!(no_carry > count / 4, "{no_carry} of {count} draws need the carry");
}
