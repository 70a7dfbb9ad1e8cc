//! Kernels are registered once. Each crate lists its kernels in one
//! [`kernel_registry!`](crate::kernel_registry) table: a kernel's name (labels, timings), its
//! WGSL file under `shaders/`, and how its defines follow from the device's [`Capabilities`].
//! Everything else follows from that table:
//! the struct of compiled kernels, the specs a stage builds its kernel from, and every variant
//! the naga test validates ([`KernelSpec::variants`] over [`every_capability_set`]).
//!
//! A new stage is its WGSL file, its Rust module, its CPU twin, its test and one line here.
use super::gpu::Kernel;
use crate::{BlockWidth, Capabilities, GpuContext, TileLayout};

/// How a kernel's defines follow from the device's capabilities.
pub type Defines = fn(&Capabilities) -> Vec<&'static str>;

/// One registered kernel.
#[derive(Clone, Copy, Debug)]
pub struct KernelSpec {
    /// The kernel's name: its resources' labels and its timings.
    pub name: &'static str,
    /// Its WGSL file under `shaders/`.
    pub file: &'static str,
    /// Its defines on a device.
    pub defines: Defines,
    /// The constants and struct declarations before its WGSL (the renderer's, or a crate's own
    /// that extends them).
    pub prelude: fn() -> String,
}

impl KernelSpec {
    /// The WGSL of the kernel with `defines`.
    pub fn source(&self, defines: &[&str]) -> Result<String, super::shader::ShaderError> {
        super::shader::compose_after((self.prelude)(), self.file, defines)
    }

    /// The kernel compiled for `ctx`'s device.
    pub fn build(&self, ctx: &GpuContext) -> Kernel {
        // The sources are compiled in and every variant is validated by a naga test, so a
        // failure here is a bug.
        #[allow(clippy::expect_used)]
        let wgsl = self
            .source(&(self.defines)(&ctx.capabilities))
            .expect("registered shaders are well formed");
        Kernel::from_wgsl(ctx, self.name, wgsl)
    }

    /// Every set of defines the kernel is compiled with on some device.
    pub fn variants(&self) -> Vec<Vec<&'static str>> {
        let mut out: Vec<Vec<&'static str>> = Vec::new();
        for caps in every_capability_set() {
            let mut defines = (self.defines)(&caps);
            defines.sort_unstable();
            if !out.contains(&defines) {
                out.push(defines);
            }
        }
        out
    }
}

/// Every combination of the capabilities that choose defines, as devices can have them (block
/// walking needs subgroups).
pub fn every_capability_set() -> Vec<Capabilities> {
    let mut out = Vec::new();
    for float_atomics in [false, true] {
        for subgroups in [false, true] {
            for block_walk in [false, true] {
                if block_walk && !subgroups {
                    continue;
                }
                for tile_layout in [TileLayout::PixelPerThread, TileLayout::RowsPerThread] {
                    for block_width in [BlockWidth::Narrow, BlockWidth::Wide] {
                        out.push(Capabilities {
                            float_atomics,
                            subgroups,
                            timestamps: false,
                            tile_layout,
                            block_width,
                            block_walk,
                            strided_groups: crate::gpu::STRIDED_GROUPS,
                            records_while_busy: true,
                        });
                    }
                }
            }
        }
    }
    out
}

/// No defines on any device.
pub fn no_defines(_: &Capabilities) -> Vec<&'static str> {
    Vec::new()
}

/// The accumulating (adjoint) kernels' defines: float atomics or the compare-exchange fallback,
/// with or without a subgroup reduction first.
pub fn accumulation(caps: &Capabilities) -> Vec<&'static str> {
    let mut d = Vec::new();
    if caps.float_atomics {
        d.push("FLOAT_ATOMICS");
    }
    if caps.subgroups {
        d.push("SUBGROUPS");
    }
    d
}

/// The pixels per thread of `rasterize_reflection` (none for one pixel per thread); why:
/// [`TileLayout`] and `shaders/shared/tile_rows.wgsl`.
pub fn tile_rows(caps: &Capabilities) -> Vec<&'static str> {
    match caps.tile_layout {
        TileLayout::PixelPerThread => Vec::new(),
        TileLayout::RowsPerThread => vec!["ROWS_PER_THREAD_4"],
    }
}

/// The pixels per thread of the adjoints' replays (`rasterize_bwd`, `rasterize_reflection_bwd`):
/// a tile column's eight rows where [`tile_rows`] gives four.
pub fn adjoint_tile_rows(caps: &Capabilities) -> Vec<&'static str> {
    match caps.tile_layout {
        TileLayout::PixelPerThread => Vec::new(),
        TileLayout::RowsPerThread => vec!["ROWS_PER_THREAD_8"],
    }
}

/// The scan and sort block width (none for [`BlockWidth::Narrow`]); why: [`BlockWidth`].
pub fn block_width(caps: &Capabilities) -> Vec<&'static str> {
    match caps.block_width {
        BlockWidth::Narrow => Vec::new(),
        BlockWidth::Wide => vec!["WIDE_BLOCKS"],
    }
}

/// Pass 1 walks by 4 x 2 pixel blocks ([`Capabilities::block_walk`]).
pub fn block_walk(caps: &Capabilities) -> Vec<&'static str> {
    if caps.block_walk { vec!["BLOCK_WALK"] } else { Vec::new() }
}

/// A table of kernels (see the module docs):
///
/// ```ignore
/// kernel_registry! {
///     /// The kernels of this crate.
///     pub const MY_KERNELS: MyKernelSpecs => MyKernels, prelude: my_prelude, {
///         adam: "training/adam.wgsl" => no_defines,
///         adam_wide: "training/adam.wgsl" => |c| [block_width(c), vec!["WIDE"]].concat(),
///     }
/// }
/// ```
///
/// makes `MY_KERNELS` (a `MyKernelSpecs` with one [`KernelSpec`] field per kernel, and
/// `all()`), and `MyKernels`, the same fields compiled (`MY_KERNELS.compile(ctx)`).
#[macro_export]
macro_rules! kernel_registry {
    (
        $(#[$meta:meta])*
        $vis:vis const $table:ident: $specs:ident => $compiled:ident, prelude: $prelude:expr, {
            $($(#[$fmeta:meta])* $field:ident : $file:literal => $defines:expr),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug)]
        $vis struct $specs {
            $($(#[$fmeta])* pub $field: $crate::toolkit::KernelSpec,)*
        }

        /// The kernels of the table, compiled for one device.
        #[derive(Debug)]
        $vis struct $compiled {
            $($(#[$fmeta])* pub $field: $crate::toolkit::Kernel,)*
        }

        $(#[$meta])*
        $vis const $table: $specs = $specs {
            $($field: $crate::toolkit::KernelSpec {
                name: stringify!($field),
                file: $file,
                defines: $defines,
                prelude: $prelude,
            },)*
        };

        impl $specs {
            /// Every kernel of the table.
            pub fn all(&self) -> Vec<$crate::toolkit::KernelSpec> {
                vec![$(self.$field),*]
            }

            /// Every kernel compiled for `ctx`'s device.
            pub fn compile(&self, ctx: &$crate::GpuContext) -> $compiled {
                $compiled { $($field: self.$field.build(ctx),)* }
            }
        }
    };
}
