// The SORT_RADIX_BITS-bit digit of one radix pass (stage `sort`) in a key or value word. The word the digit is
// in is bound a second time as `digit_words` (the caller binds the key or the value buffer there),
// so that counting reads one word per key instead of both.
fn digit_in(word: u32) -> u32 {
    return (word >> params.shift) & (SORT_RADIX - 1u);
}
