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
