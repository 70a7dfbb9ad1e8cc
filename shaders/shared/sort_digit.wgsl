// The 4-bit digit of one radix pass (stage `sort`). Uses the including file's `params`
// (SortParams), `keys` and `values` bindings.
fn digit_of(slot: u32) -> u32 {
    var word = values[slot];
    if params.from_keys != 0u {
        word = keys[slot];
    }
    return (word >> params.shift) & 15u;
}
