// Gradient accumulation into the f32 buffer `grads`, which the including shader declares as
//   #ifdef FLOAT_ATOMICS  var<storage, read_write> grads: array<atomic<f32>>;
//   #else                 var<storage, read_write> grads: array<atomic<u32>>;  (f32 bits)
// With float atomics, an atomic add; without, a compare-exchange loop on the bits (slower under
// contention, same sum up to the order of additions). `accumulate_subgroup` first sums the value
// over the subgroup and lets one lane add it: it must be called in uniform control flow, with
// zero from lanes that have nothing to add.

fn accumulate(i: u32, v: f32) {
#ifdef FLOAT_ATOMICS
    atomicAdd(&grads[i], v);
#else
    var old = atomicLoad(&grads[i]);
    loop {
        let new_bits = bitcast<u32>(bitcast<f32>(old) + v);
        let r = atomicCompareExchangeWeak(&grads[i], old, new_bits);
        if r.exchanged {
            break;
        }
        old = r.old_value;
    }
#endif
}

#ifdef SUBGROUPS
fn accumulate_subgroup(i: u32, v: f32) {
    let total = subgroupAdd(v);
    // The first active lane adds (naga has no subgroupElect).
    let first = subgroupExclusiveAdd(1u) == 0u;
    if first && total != 0.0 {
        accumulate(i, total);
    }
}
#else
fn accumulate_subgroup(i: u32, v: f32) {
    if v != 0.0 {
        accumulate(i, v);
    }
}
#endif
