//! Stage `sort`: a stable sort of the (key, value) pairs by key, as the GPU's LSD radix sort does
//! (stable: equal keys keep the emission order, i.e. Gaussian index order).
pub fn sort_keys(keys: &mut [u64], values: &mut [u32]) {
    let mut pairs: Vec<(u64, u32)> = keys.iter().copied().zip(values.iter().copied()).collect();
    pairs.sort_by_key(|&(k, _)| k);
    for (slot, (k, v)) in pairs.into_iter().enumerate() {
        keys[slot] = k;
        values[slot] = v;
    }
}
