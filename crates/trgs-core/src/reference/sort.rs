//! Stage `sort`: a stable sort of the (tile, value) pairs by tile, as the GPU's LSD radix sort
//! does (stable: equal tiles keep the emission order, which `depth_order` made front to back).
pub fn sort_keys(keys: &mut [u32], values: &mut [u32]) {
    let mut pairs: Vec<(u32, u32)> = keys.iter().copied().zip(values.iter().copied()).collect();
    pairs.sort_by_key(|&(k, _)| k);
    for (slot, (k, v)) in pairs.into_iter().enumerate() {
        keys[slot] = k;
        values[slot] = v;
    }
}
