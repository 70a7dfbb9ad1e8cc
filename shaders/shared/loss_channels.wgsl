// The colour channels one run of `photometric_loss`'s four passes works on. RGB: all three at
// once, each tap's pixel read once for the three (used when three channels' scratch buffers fit
// one binding). Otherwise the one channel `params.channel`, and the passes run once per channel.
// Loops over `LOSS_CHANNELS` have a constant count, so they unroll and their private arrays keep
// constant indices (a dynamic index puts a private array in memory on lavapipe).
#ifdef RGB
const LOSS_CHANNELS: u32 = 3u;
// The colour component of channel `c` of this run.
fn loss_channel(c: u32) -> u32 {
    return c;
}
#else
const LOSS_CHANNELS: u32 = 1u;
fn loss_channel(c: u32) -> u32 {
    return params.channel;
}
#endif
// Values per pixel in the scratch buffers: five moments (passes 1-2), three derivatives
// (passes 2-4), per channel of the run.
const LOSS_MOMENTS: u32 = 5u * LOSS_CHANNELS;
const LOSS_TERMS: u32 = 3u * LOSS_CHANNELS;

// The sliding window of passes 2-4: a thread blurs LOSS_BLUR_RUN consecutive pixels along the
// pass's direction (rows: x, columns: y), so that the SSIM_TAPS - 1 + LOSS_BLUR_RUN pixels it
// reads serve all of them, where a thread per pixel read each pixel SSIM_TAPS times (every read
// of a storage buffer is a gather on a CPU adapter). Input i of the run (pixel first + i -
// SSIM_RADIUS) meets output r with the window's tap i - r, in the same order of taps as a
// per-pixel loop, so the sums are the same. Pass 1 keeps a thread per pixel: it reads two values
// a tap and keeps fifteen sums a pixel, and its runs were slower.
const SSIM_TAPS: u32 = 2u * SSIM_RADIUS + 1u;
const LOSS_BLUR_INPUTS: u32 = LOSS_BLUR_RUN + SSIM_TAPS - 1u;

// The tap of the window by which input `i` of a run enters output `r`: SSIM_TAPS or more where
// it does not (i < r wraps to a large u32).
fn blur_tap(i: u32, r: u32) -> u32 {
    return i - r;
}
