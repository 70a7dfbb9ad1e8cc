// The SORT_RADIX_BITS-bit digit of one radix pass (stage `sort`) in a key. Uses the including
// file's `params` (SortParams).
fn digit_in(word: u32) -> u32 {
    return (word >> params.shift) & (SORT_RADIX - 1u);
}
