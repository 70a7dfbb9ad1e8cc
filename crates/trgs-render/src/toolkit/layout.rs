//! GPU struct layouts, with one source of truth: each struct is declared once here, and the WGSL
//! declaration every shader sees is generated from the Rust one (see [`prelude`]). The constants
//! the kernels share with the CPU twin (tile size, alpha and transmittance thresholds, the EWA
//! blur, SH constants) come from `trgs_core` the same way. A test compares every struct's field
//! offsets and size with naga's layout of the generated WGSL, so a field whose WGSL alignment
//! differs from its Rust position fails instead of drifting.
use trgs_core::pipeline::{
    COV2D_BLUR, DEPTH_KEY_BITS, MAX_ALPHA, MIN_ALPHA, MIN_TRANSMITTANCE, ReflectionModel,
    TILE_PIXELS, TILE_SIZE,
};
use trgs_core::sh;

/// A Rust type with a WGSL spelling.
pub trait WgslType {
    const WGSL: &'static str;
}

macro_rules! wgsl_type {
    ($($t:ty => $w:literal),* $(,)?) => { $(impl WgslType for $t { const WGSL: &'static str = $w; })* };
}
wgsl_type!(
    f32 => "f32", u32 => "u32", [f32; 2] => "vec2<f32>", [f32; 4] => "vec4<f32>",
    [u32; 2] => "vec2<u32>", [u32; 4] => "vec4<u32>",
);

/// A `#[repr(C)]` Pod struct shared with WGSL.
pub trait GpuStruct: bytemuck::Pod {
    const NAME: &'static str;
    /// The WGSL declaration.
    fn wgsl() -> String;
    /// (field, byte offset) in declaration order.
    fn field_offsets() -> Vec<(&'static str, usize)>;
}

/// Declares a `#[repr(C)]` Pod struct shared with WGSL: the Rust struct and its [`GpuStruct`]
/// impl (its WGSL declaration and field offsets, which a test compares with naga's layout).
#[macro_export]
macro_rules! gpu_struct {
    ($(#[$meta:meta])* pub struct $name:ident { $($(#[$fmeta:meta])* pub $field:ident : $ty:ty),* $(,)? }) => {
        $(#[$meta])*
        #[repr(C)]
        #[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
        pub struct $name { $($(#[$fmeta])* pub $field: $ty),* }

        impl $crate::toolkit::layout::GpuStruct for $name {
            const NAME: &'static str = stringify!($name);
            fn wgsl() -> String {
                let mut s = format!("struct {} {{\n", stringify!($name));
                $(s.push_str(&format!(
                    "    {}: {},\n",
                    stringify!($field),
                    <$ty as $crate::toolkit::layout::WgslType>::WGSL
                ));)*
                s.push_str("}\n");
                s
            }
            fn field_offsets() -> Vec<(&'static str, usize)> {
                vec![$((stringify!($field), std::mem::offset_of!($name, $field))),*]
            }
        }
    };
}

gpu_struct! {
    /// Parameters of `project`: one view (real or mirrored camera) and its culling rules.
    pub struct ProjectParams {
        /// Rows of the view's 3x3 linear map (a rotation, or R H for a mirrored camera).
        pub row0: [f32; 4],
        pub row1: [f32; 4],
        pub row2: [f32; 4],
        pub translation: [f32; 4],
        /// The view's own centre (H(c) for a mirrored camera): the SH view direction's origin.
        pub centre: [f32; 4],
        /// Front-side filter of a mirrored view: plane centre and unit normal.
        pub plane_centre: [f32; 4],
        pub plane_normal: [f32; 4],
        /// (fx, fy, cx, cy)
        pub focal: [f32; 4],
        /// Guard band of the Jacobian: (x/z min, x/z max, y/z min, y/z max).
        pub tan_limits: [f32; 4],
        /// Gaussians touching no tile of (x0, y0, x1, y1) are culled before their SH.
        pub limit: [u32; 4],
        /// Gaussians in this dispatch (the bindings are ranges of the scene's buffers).
        pub count: u32,
        pub sh_degree: u32,
        /// SH coefficients per colour channel stored per Gaussian.
        pub sh_coeffs: u32,
        /// 1 for a mirrored view: only primary Gaussians strictly in front of the plane.
        pub front_only: u32,
        pub near: f32,
        pub width: u32,
        pub height: u32,
        /// `project_bwd` only: BWD_* bits (how to write the Gaussians' and the view's gradients).
        pub bwd_mode: u32,
    }
}

gpu_struct! {
    /// One projected Gaussian (twin: `reference::Projected`, one entry of each array).
    pub struct ProjectedGaussian {
        /// Pixel coordinates of the mean (pixel centres at +0.5).
        pub mean2d: [f32; 2],
        /// Half-extents of the box where alpha can reach 1/255.
        pub extent: [f32; 2],
        /// Inverse 2D covariance (a, b, c) and the opacity.
        pub conic: [f32; 4],
        /// Colour after the clamp at zero, and the camera-space depth.
        pub color: [f32; 4],
        /// Glass mask value m (zero for primary Gaussians).
        pub mask: f32,
        /// Reflection intensity a.
        pub reflection: f32,
        /// FLAG_* bits.
        pub flags: u32,
        pub pad: u32,
    }
}

gpu_struct! {
    /// Parameters of `tile_counts` (one view, one chunk of the scene).
    pub struct TileParams {
        pub width: u32,
        pub height: u32,
        pub tiles_x: u32,
        pub tiles_y: u32,
        /// Tiles outside (x0, y0, x1, y1) are not binned (a plane's footprint).
        pub limit: [u32; 4],
        /// Gaussians in this dispatch and the index of the first one.
        pub count: u32,
        pub first: u32,
        /// The frame numbers every (view, Gaussian) pair `entry_base + Gaussian index`, with
        /// `entry_base = view * Gaussians`: the entries of the one depth order of all views.
        pub entry_base: u32,
        /// Index of the view (its key total is `key_totals[2 view]`, with its carries after).
        pub view: u32,
        /// The f32 bits the depth-order keys count from
        /// (`trgs_core::pipeline::depth_key_base` of the near plane).
        pub depth_base: u32,
        pub pad0: u32,
        pub pad1: u32,
        pub pad2: u32,
    }
}

gpu_struct! {
    /// Parameters of `emit_keys`: the entries in depth order, over every view at once.
    pub struct EmitParams {
        /// Entries in the depth order.
        pub entries: u32,
        /// Gaussians in the scene (an entry's view is entry / gaussians).
        pub gaussians: u32,
        /// Pairs in the key list's first page ([`crate::toolkit::paged`]); the rest are in the
        /// second.
        pub page: u32,
        /// Pairs the key list holds: keys past it are dropped (a list sized from earlier frames
        /// that this one outgrew; the renderer reads the true total back and says so).
        pub capacity: u32,
    }
}

gpu_struct! {
    /// How `emit_keys` numbers one view's tiles in the shared key list: row by row within its
    /// limit (x0, y0, row length), from `tile_base`.
    pub struct ViewTiles {
        pub tile_base: u32,
        pub x0: u32,
        pub y0: u32,
        pub row: u32,
    }
}

gpu_struct! {
    /// Parameters of `prefix_sum`, `prefix_sum_add`, `tile_ranges` and the `depth_order`
    /// kernels: `count` values (the compaction's are words of the presence bit mask).
    pub struct ScanParams {
        pub count: u32,
        /// `prefix_sum`'s level scan: the blocks of the dispatch (of its capacity when the
        /// count is known on the GPU only), each of which writes its total.
        pub blocks: u32,
        /// The workgroup permutation's step ([`crate::gpu::spread_step`]; 0: none).
        pub spread: u32,
        /// `tile_ranges`: keys in the key list's first page ([`crate::toolkit::paged`]).
        pub page: u32,
    }
}

gpu_struct! {
    /// Parameters of one radix pass of `sort`.
    pub struct SortParams {
        pub count: u32,
        /// Bit offset of the digit (SORT_RADIX_BITS wide) in its word.
        pub shift: u32,
        /// The workgroup permutation's step ([`crate::gpu::spread_step`]; 0: none).
        pub spread: u32,
        pub num_blocks: u32,
        /// Pairs in the first page of the list ([`crate::toolkit::paged`]); the rest are in the
        /// second.
        pub page: u32,
        pub pad1: u32,
        pub pad2: u32,
        pub pad3: u32,
    }
}

gpu_struct! {
    /// Parameters of `rasterize` and `rasterize_reflection`.
    pub struct RasterParams {
        pub width: u32,
        pub height: u32,
        pub tiles_x: u32,
        pub tiles_y: u32,
        /// First tile of the dispatch (a plane's footprint corner; 0 for pass 1).
        pub tile_x0: u32,
        pub tile_y0: u32,
        /// Plane slot of pass 2's outputs.
        pub slot: u32,
        /// `rasterize_bwd` only: 1 when the frame has the depth-variance layer (else dL/dV is
        /// ignored: V was never computed).
        pub depth_variance: u32,
        /// The sorted tile index of the dispatch's first tile and the width of its tile rectangle
        /// in tiles (ViewTiles::tile_base; the whole grid's width for pass 1).
        pub tile_base: u32,
        pub tiles_w: u32,
        /// Gaussians in the first page of the projected records and their gradients
        /// ([`crate::toolkit::paged`]); the rest are in the second.
        pub page: u32,
        /// Values in the first page of the sorted key list; the rest are in the second.
        pub key_page: u32,
        /// Colour behind the last transmittance of C_t.
        pub background: [f32; 4],
    }
}

gpu_struct! {
    /// What the backward replay needs of one pixel of pass 1 (twin: `reference::PixelState`).
    pub struct RasterState {
        pub t_final: f32,
        pub tm_final: f32,
        pub last_t: u32,
        pub last_m: u32,
        pub weight_sum: f32,
        pub depth_sign_sum: f32,
    }
}

gpu_struct! {
    /// What the backward replay needs of one pixel of pass 2.
    pub struct ReflectionState {
        pub t_final: f32,
        pub last: u32,
    }
}

gpu_struct! {
    /// Parameters of `compose`: the real camera's rays.
    pub struct ComposeParams {
        pub width: u32,
        pub height: u32,
        pub num_planes: u32,
        /// `MODEL_*` bits: parts of the reflection model switched off (ablations).
        pub model: u32,
        /// (fx, fy, cx, cy)
        pub focal: [f32; 4],
        /// Camera centre in world space.
        pub origin: [f32; 4],
        /// Columns of the camera-to-world rotation.
        pub cam_col0: [f32; 4],
        pub cam_col1: [f32; 4],
        pub cam_col2: [f32; 4],
    }
}

gpu_struct! {
    /// A reflection plane as `compose` sees it.
    pub struct PlaneGpu {
        /// Centre, and R0 in w.
        pub centre: [f32; 4],
        /// Unit normal, and in w 1 when the plane's mirrored pass ran (camera in front).
        pub normal: [f32; 4],
        /// Unit width direction t, and half the width in w.
        pub axis: [f32; 4],
        /// b = n x t, and half the height in w.
        pub bitangent: [f32; 4],
    }
}

/// Entries per workgroup of `depth_order_counts`: its 256 threads take DEPTH_COUNTS_BLOCK / 256
/// each.
pub const DEPTH_COUNTS_BLOCK: u32 = 1024;
const _: () = assert!(DEPTH_COUNTS_BLOCK.is_multiple_of(256), "whole rounds of 256 threads");

/// `ProjectedGaussian::flags` bits.
pub const FLAG_VISIBLE: u32 = 1;
pub const FLAG_GLASS: u32 = 2;
pub const FLAG_CLAMPED_R: u32 = 4;
pub const FLAG_CLAMPED_G: u32 = 8;
pub const FLAG_CLAMPED_B: u32 = 16;
/// Floats per Gaussian in a view's screen-space gradient buffer (twin: `ProjectedGrads`), as
/// three vec4: (dmean2d.xy, dopacity, ddepth), (dconic a b c, dmask), (dcolour rgb, dreflection).
pub const PROJECTED_GRAD_FLOATS: u32 = 12;
/// Floats per view in the view-gradient buffer (twin: `ViewGrads`): the linear map by columns
/// (9), the translation (3), the centre (3), one pad.
pub const VIEW_GRAD_FLOATS: u32 = 16;
/// Floats per plane in the backward's plane accumulator (compose_bwd sums into it): dL/dR0 and
/// dL/d(unit normal).
pub const PLANE_GRAD_FLOATS: u64 = 4;
/// `ProjectParams::bwd_mode` bits. ADD: add into the Gaussian gradients (a mirrored view) instead
/// of writing them (the primary view writes every Gaussian's, zero for culled ones); it picks
/// `project_bwd`'s ADD_GRADIENTS variant. NO_GAUSSIANS:
/// leave them alone (stage 2's stop-gradient). VIEW: sum the view's gradient.
pub const BWD_ADD: u32 = 1;
pub const BWD_NO_GAUSSIANS: u32 = 2;
pub const BWD_VIEW: u32 = 4;
gpu_struct! {
    /// Parameters of `display`: a layer to 8-bit RGBA (trgs_core::pipeline::DisplayMapping).
    pub struct DisplayParams {
        pub width: u32,
        pub height: u32,
        /// Words (pixels) from one output row to the next: the width padded to 256 bytes.
        pub row_pixels: u32,
        /// 0 RGB, 1 gray, 2 inverse depth, 3 black.
        pub mode: u32,
        /// The vec4 component read by modes 1 and 2.
        pub channel: u32,
        pub near: f32,
        pub far: f32,
        pub _pad: u32,
    }
}

/// `ComposeParams::model` bits (trgs_core::pipeline::ReflectionModel).
pub const MODEL_NO_FRESNEL: u32 = 1;
pub const MODEL_NO_INTENSITY: u32 = 2;
/// `Population::Glass` as stored in the population buffer.
pub const POPULATION_GLASS: u32 = 1;
/// Threads and values per thread of the prefix sum (few threads, many values each, for the
/// reason given at SORT_THREADS); a workgroup takes SCAN_THREADS times the items of the device's
/// [`crate::BlockWidth`].
pub const SCAN_THREADS: u32 = 64;
pub const SCAN_ITEMS: u32 = 16;
/// Values per thread of the prefix sum with [`crate::BlockWidth::Wide`] (CPU adapters).
pub const SCAN_ITEMS_WIDE: u32 = 64;
/// Threads and keys per thread of a radix pass (a block is SORT_THREADS times the items of the
/// device's [`crate::BlockWidth`]). Few threads with many keys each: the scatter's in-workgroup
/// scan costs log2(threads) barrier rounds, and a barrier is expensive on CPU adapters (lavapipe
/// switches every invocation's context at each one), while the per-thread serial part is cheap
/// everywhere. 16-bit packed counters need a block below 65536 keys.
pub const SORT_THREADS: u32 = 64;
/// The most workgroups along one dimension of a dispatch (WebGPU's and Vulkan's minimum limit).
pub const MAX_WORKGROUPS: u32 = 65_535;
pub const SORT_ITEMS: u32 = 64;
/// Keys per thread of a radix pass with [`crate::BlockWidth::Wide`] (CPU adapters).
pub const SORT_ITEMS_WIDE: u32 = 256;
/// Bits per radix-sort digit. Six: a pass costs about the same with 16 or 64 digits on lavapipe
/// (moving the keys is the cost), and 64 digits sort the 30 bits of the depth keys in 5 passes
/// instead of 8 and the tile indices of a 256x192 or 512x384 frame in 2 instead of 3. Each thread
/// keeps one 16-bit counter per digit (SORT_PACKED words).
pub const SORT_RADIX_BITS: u32 = 6;
pub const SORT_RADIX: u32 = 1 << SORT_RADIX_BITS;
pub const SORT_PACKED: u32 = SORT_RADIX / 2;
pub const SORT_PACKED_VECS: u32 = SORT_PACKED / 4;

/// One GPU struct: (name, WGSL declaration, Rust field offsets, Rust size).
pub type StructInfo = (&'static str, String, Vec<(&'static str, usize)>, usize);

/// The name, WGSL declaration, Rust field offsets and Rust size of `T`.
pub fn struct_info<T: GpuStruct>() -> StructInfo {
    (T::NAME, T::wgsl(), T::field_offsets(), std::mem::size_of::<T>())
}

/// Every GPU struct of the renderer.
pub fn all_structs() -> Vec<StructInfo> {
    vec![
        struct_info::<ProjectParams>(),
        struct_info::<ProjectedGaussian>(),
        struct_info::<TileParams>(),
        struct_info::<EmitParams>(),
        struct_info::<ViewTiles>(),
        struct_info::<ScanParams>(),
        struct_info::<SortParams>(),
        struct_info::<RasterParams>(),
        struct_info::<RasterState>(),
        struct_info::<ReflectionState>(),
        struct_info::<ComposeParams>(),
        struct_info::<DisplayParams>(),
        struct_info::<PlaneGpu>(),
    ]
}

/// `v` as a WGSL f32 literal.
pub fn float(v: f64) -> String {
    format!("{:?}", v as f32)
}

/// WGSL declarations of `u32` and `f32` constants.
pub fn wgsl_constants(u32s: &[(&str, u32)], f32s: &[(String, f64)]) -> String {
    let mut s = String::new();
    for (name, v) in u32s {
        s.push_str(&format!("const {name}: u32 = {v}u;\n"));
    }
    for (name, v) in f32s {
        s.push_str(&format!("const {name}: f32 = {};\n", float(*v)));
    }
    s
}

/// The `ComposeParams::model` bits of `model`.
pub fn model_bits(model: ReflectionModel) -> u32 {
    (if model.fresnel { 0 } else { MODEL_NO_FRESNEL })
        | (if model.intensity { 0 } else { MODEL_NO_INTENSITY })
}

/// Views whose cheap culls one `project_candidates` dispatch runs (its bindings are per view:
/// a frame with more views runs it once per group).
pub const CULL_VIEWS: u32 = 3;

/// The text every renderer shader starts with: the constants and struct declarations above
/// (trgs-train's prelude extends it with its own).
pub fn prelude() -> String {
    let mut s =
        String::from("// Generated by trgs-render (layout.rs): do not edit in the .wgsl files.\n");
    let consts_u32 = [
        ("TILE_SIZE", TILE_SIZE),
        ("TILE_PIXELS", TILE_PIXELS),
        ("FLAG_VISIBLE", FLAG_VISIBLE),
        ("FLAG_GLASS", FLAG_GLASS),
        ("FLAG_CLAMPED_R", FLAG_CLAMPED_R),
        ("FLAG_CLAMPED_G", FLAG_CLAMPED_G),
        ("FLAG_CLAMPED_B", FLAG_CLAMPED_B),
        ("POPULATION_GLASS", POPULATION_GLASS),
        ("SCAN_ITEMS_NARROW", SCAN_ITEMS),
        ("SCAN_ITEMS_WIDE", SCAN_ITEMS_WIDE),
        ("SORT_ITEMS_NARROW", SORT_ITEMS),
        ("SORT_ITEMS_WIDE", SORT_ITEMS_WIDE),
        ("SORT_THREADS", SORT_THREADS),
        ("SCAN_THREADS", SCAN_THREADS),
        ("SORT_RADIX", SORT_RADIX),
        ("SORT_PACKED", SORT_PACKED),
        ("SORT_PACKED_VECS", SORT_PACKED_VECS),
        ("PROJECTED_GRAD_FLOATS", PROJECTED_GRAD_FLOATS),
        ("VIEW_GRAD_FLOATS", VIEW_GRAD_FLOATS),
        ("BWD_ADD", BWD_ADD),
        ("BWD_NO_GAUSSIANS", BWD_NO_GAUSSIANS),
        ("BWD_VIEW", BWD_VIEW),
        ("MODEL_NO_FRESNEL", MODEL_NO_FRESNEL),
        ("MODEL_NO_INTENSITY", MODEL_NO_INTENSITY),
        ("DEPTH_KEY_BITS", DEPTH_KEY_BITS),
        ("CULL_VIEWS", CULL_VIEWS),
        ("DEPTH_COUNTS_BLOCK", DEPTH_COUNTS_BLOCK),
    ];
    let mut consts_f32 = vec![
        ("MAX_ALPHA".to_string(), MAX_ALPHA),
        ("MIN_ALPHA".to_string(), MIN_ALPHA),
        ("MIN_TRANSMITTANCE".to_string(), MIN_TRANSMITTANCE),
        ("COV2D_BLUR".to_string(), COV2D_BLUR),
        ("SH_C0".to_string(), sh::C0),
        ("SH_C1".to_string(), sh::C1),
    ];
    consts_f32.extend(sh::C2.iter().enumerate().map(|(i, &v)| (format!("SH_C2_{i}"), v)));
    consts_f32.extend(sh::C3.iter().enumerate().map(|(i, &v)| (format!("SH_C3_{i}"), v)));
    s.push_str(&wgsl_constants(&consts_u32, &consts_f32));
    for (_, decl, _, _) in all_structs() {
        s.push_str(&decl);
    }
    s
}
