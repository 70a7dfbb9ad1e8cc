// How a per-tile kernel gives the tile's pixels to threads (trgs_render::TileLayout): each
// thread takes ROWS consecutive rows of one column, so a workgroup is TILE_SIZE x
// (TILE_SIZE / ROWS) threads and a batch of TILE_PIXELS entries takes ROWS loads per thread.
// One row on a GPU. On a CPU adapter four in `rasterize_reflection` (the define
// ROWS_PER_THREAD_4) and the whole column of eight in the adjoints (ROWS_PER_THREAD_8): there a
// subgroup is one SIMD vector and a workgroup's subgroups run one after another, each paying
// every list entry's loads and loop control, and in the adjoints a subgroup reduction and its
// atomics (loops over the lanes), however few of its pixels use the entry; the rows share them (docs/gpu-renderer.md, "Choices per adapter"). With eight, one
// subgroup is the whole tile and makes one reduction per entry.
#ifdef ROWS_PER_THREAD_8
const ROWS: u32 = 8u;
#else
#ifdef ROWS_PER_THREAD_4
const ROWS: u32 = 4u;
#else
const ROWS: u32 = 1u;
#endif
#endif
const THREADS: u32 = TILE_PIXELS / ROWS;
