// Reading a key list held in pages of one binding each (toolkit::paged). With PAGED (the kernels'
// variant for a list of two pages) the first `params.page` keys are in `keys`, the rest in
// `keys_hi`, which the including shader then binds. Without it there is one page, read as it is.

#ifdef PAGED
fn key_at(i: u32) -> u32 {
    if i < params.page {
        return keys[i];
    }
    return keys_hi[i - params.page];
}
#else
fn key_at(i: u32) -> u32 {
    return keys[i];
}
#endif
