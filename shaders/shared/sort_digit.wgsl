// The 4-bit digit of one radix pass (stage `sort`). Uses the including file's `params`
// (SortParams), `keys_hi` and `keys_lo` bindings.
fn digit_of(slot: u32) -> u32 {
    var word = keys_lo[slot];
    if params.use_hi != 0u {
        word = keys_hi[slot];
    }
    return (word >> params.shift) & 15u;
}
