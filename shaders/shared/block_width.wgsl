// Values per thread and per workgroup of `prefix_sum` and of the radix sort's passes, for the
// device's BlockWidth (trgs_render::BlockWidth): the prelude has both widths' item counts, the
// WIDE_BLOCKS define picks the CPU adapters' one.
#ifdef WIDE_BLOCKS
const SCAN_ITEMS: u32 = SCAN_ITEMS_WIDE;
const SORT_ITEMS: u32 = SORT_ITEMS_WIDE;
#else
const SCAN_ITEMS: u32 = SCAN_ITEMS_NARROW;
const SORT_ITEMS: u32 = SORT_ITEMS_NARROW;
#endif
const SCAN_BLOCK: u32 = SCAN_THREADS * SCAN_ITEMS;
const SORT_BLOCK: u32 = SORT_THREADS * SORT_ITEMS;
