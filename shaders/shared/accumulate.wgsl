// Gradient accumulation into the f32 buffer `grads`, which the including shader declares as
//   #ifdef FLOAT_ATOMICS  var<storage, read_write> grads: array<atomic<f32>>;
//   #else                 var<storage, read_write> grads: array<atomic<u32>>;  (f32 bits)
// With float atomics, an atomic add; without, a compare-exchange loop on the bits (slower under
// contention, same sum up to the order of additions). `accumulate_subgroup` first sums the value
// over the subgroup and lets one lane add it: it must be called in uniform control flow, with
// zero from lanes that have nothing to add. `subgroup_any` guards a group of them: its result is
// the same on every lane of a subgroup, so every lane still takes part in each reduction.

// The atomic add of v to grads[i].
fn add_to_grads(i: u32, v: f32) {
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

#ifdef PAGED
// With PAGED the gradient records are in two pages (toolkit::paged): those of the first
// params.page Gaussians in `grads`, the rest in `grads_hi`, which the including shader declares
// as it declares `grads`. The loop is written out again for `grads_hi`: a function cannot take
// a pointer to a storage buffer without WGSL's unrestricted_pointer_parameters.
fn add_to_grads_hi(i: u32, v: f32) {
#ifdef FLOAT_ATOMICS
    atomicAdd(&grads_hi[i], v);
#else
    var old = atomicLoad(&grads_hi[i]);
    loop {
        let new_bits = bitcast<u32>(bitcast<f32>(old) + v);
        let r = atomicCompareExchangeWeak(&grads_hi[i], old, new_bits);
        if r.exchanged {
            break;
        }
        old = r.old_value;
    }
#endif
}

fn accumulate(i: u32, v: f32) {
    let first = params.page * PROJECTED_GRAD_FLOATS;
    if i < first {
        add_to_grads(i, v);
    } else {
        add_to_grads_hi(i - first, v);
    }
}
#else
fn accumulate(i: u32, v: f32) {
    add_to_grads(i, v);
}
#endif

#ifdef SUBGROUPS
// The largest x over the subgroup.
fn subgroup_max(x: u32) -> u32 {
    return subgroupMax(x);
}

// Whether any lane of the subgroup has `b` (lets a whole subgroup skip its reductions).
fn subgroup_any(b: bool) -> bool {
    return subgroupAny(b);
}

// Four values at once into grads[base + c] (one reduction of a vector instead of four).
fn accumulate_subgroup4(base: u32, v: vec4<f32>) {
    let total = subgroupAdd(v);
    let first = subgroupExclusiveAdd(1u) == 0u;
    if first {
        for (var c = 0u; c < 4u; c++) {
            if total[c] != 0.0 {
                accumulate(base + c, total[c]);
            }
        }
    }
}

// A Gaussian's record of three vec4 at grads[base ..]: one reduction per vector, then the lanes
// share the atomics (lane l adds the components l, l + size, ...) instead of one lane making
// them all in turn. The rank and the count are taken here, among the lanes that make the
// reductions: ranks carried from the top of a kernel would leave a share of the sums unadded
// wherever a driver has not reconverged the subgroup after a divergent branch (Vulkan promises
// reconvergence only with maximal reconvergence).
fn accumulate_subgroup12(base: u32, g: array<vec4<f32>, 3>) {
    let t = array<vec4<f32>, 3>(subgroupAdd(g[0]), subgroupAdd(g[1]), subgroupAdd(g[2]));
    let lane = subgroupExclusiveAdd(1u);
    let size = subgroupAdd(1u);
    for (var c = lane; c < 12u; c += size) {
        let v = t[c / 4u][c % 4u];
        if v != 0.0 {
            accumulate(base + c, v);
        }
    }
}

fn accumulate_subgroup(i: u32, v: f32) {
    let total = subgroupAdd(v);
    // The first active lane adds (naga has no subgroupElect).
    let first = subgroupExclusiveAdd(1u) == 0u;
    if first && total != 0.0 {
        accumulate(i, total);
    }
}
#else
fn subgroup_max(x: u32) -> u32 {
    return x;
}

fn subgroup_any(b: bool) -> bool {
    return b;
}

fn accumulate_subgroup4(base: u32, v: vec4<f32>) {
    for (var c = 0u; c < 4u; c++) {
        if v[c] != 0.0 {
            accumulate(base + c, v[c]);
        }
    }
}

fn accumulate_subgroup12(base: u32, g: array<vec4<f32>, 3>) {
    for (var c = 0u; c < 12u; c++) {
        let v = g[c / 4u][c % 4u];
        if v != 0.0 {
            accumulate(base + c, v);
        }
    }
}

fn accumulate_subgroup(i: u32, v: f32) {
    if v != 0.0 {
        accumulate(i, v);
    }
}
#endif
