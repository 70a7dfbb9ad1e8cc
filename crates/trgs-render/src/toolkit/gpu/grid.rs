//! Workgroup grids of 1D dispatches, and the order in which their workgroups take blocks.

/// Workgroup counts for `groups` workgroups of a 1D dispatch, split into 2D past the 65,535 limit
/// (the kernels rebuild the linear index with `linear_index`, or take their block with
/// `spread_block`, both in shaders/shared/common.wgsl).
pub fn grid_1d(groups: u32) -> [u32; 3] {
    const MAX: u32 = crate::layout::MAX_WORKGROUPS;
    if groups <= MAX { [groups, 1, 1] } else { [MAX, groups.div_ceil(MAX), 1] }
}

/// Workgroups of a strided dispatch at most on a GPU: enough to fill a large one (a million
/// threads of 256-thread workgroups).
pub const STRIDED_GROUPS: u32 = 4096;

/// Workgroups of a strided dispatch at most on a CPU adapter: a few per thread of a large CPU.
/// lavapipe hands each thread one contiguous run of the workgroups, so a dispatch of more, over
/// a capacity whose count fills only its first blocks, leaves the work to the first thread (see
/// [`spread_step`]); strided, every workgroup takes an equal share of the blocks below the count.
pub const STRIDED_GROUPS_CPU: u32 = 64;

/// The strided dispatch's workgroups for an adapter of this type.
pub fn strided_groups_for(device_type: wgpu::DeviceType) -> u32 {
    match device_type {
        wgpu::DeviceType::Cpu => STRIDED_GROUPS_CPU,
        _ => STRIDED_GROUPS,
    }
}

/// Workgroup counts of a strided dispatch over `blocks` blocks: at most `most` workgroups
/// (`Capabilities::strided_groups`; at least one), each taking blocks `w, w + groups, ...`
/// below the count the kernel reads (`strided_first` and `strided_step` in
/// shaders/shared/common.wgsl). Why: a count known on the GPU only leaves most blocks of a
/// dispatch over its capacity empty, and on lavapipe every empty workgroup still costs its
/// launch; strided workgroups visit only the blocks below the count, each its share of them.
pub fn strided_grid(blocks: u32, most: u32) -> [u32; 3] {
    grid_1d(blocks.clamp(1, most.max(1)))
}

/// 1 / golden ratio: the step fraction whose multiples mod 1 are the most evenly spread.
const INVERSE_GOLDEN_RATIO: f64 = 0.618_033_988_749_894_8;

/// The step of the workgroup permutation of a 1D dispatch of `groups` ([`spread_block`]): the
/// first step at or above n / golden ratio that is coprime to n, the size of the spread
/// dimension (the rows of a split dispatch, else its workgroups), so that every run of
/// consecutive workgroups takes blocks spread over the whole range; 0 (none) where n is at most
/// 2.
///
/// Why: lavapipe hands each of its threads one contiguous run of a dispatch's workgroups
/// (workgroups / threads each, no stealing), so a dispatch that covers a capacity while its
/// count is known on the GPU only, all its work in the first blocks, ran on one thread while the
/// others passed over empty blocks (the depth order's sort at 100k Gaussians with a plane: 6 of
/// 13 workgroups full, all in the first thread's run).
pub fn spread_step(groups: [u32; 3]) -> u32 {
    debug_assert_eq!(groups[2], 1, "a 1D dispatch, split into rows at most");
    let n = if groups[1] > 1 { groups[1] } else { groups[0] };
    if n <= 2 {
        return 0;
    }
    let gcd = |mut a: u32, mut b: u32| {
        while b != 0 {
            (a, b) = (b, a % b);
        }
        a
    };
    let mut step = (f64::from(n) * INVERSE_GOLDEN_RATIO) as u32;
    while gcd(step, n) != 1 {
        step += 1;
    }
    step
}

/// The block that workgroup `wid` of a dispatch of `groups` takes with `step`: the twin of
/// `spread_block` in shaders/shared/common.wgsl (a split dispatch spreads its rows).
pub fn spread_block(wid: [u32; 2], groups: [u32; 3], step: u32) -> u32 {
    let ([x, y], [nx, ny]) = (wid, [groups[0], groups[1]]);
    if step == 0 {
        x + y * nx
    } else if ny == 1 {
        (x * step) % nx
    } else {
        ((y * step) % ny) * nx + x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The blocks of a dispatch of `groups`, workgroup by workgroup in lavapipe's order (x
    /// fastest).
    fn spread_blocks(groups: [u32; 3]) -> Vec<u32> {
        let step = spread_step(groups);
        (0..groups[1])
            .flat_map(|y| (0..groups[0]).map(move |x| [x, y]))
            .map(|wid| spread_block(wid, groups, step))
            .collect()
    }

    /// How many of the first `full` blocks each of `threads` runs of consecutive workgroups
    /// takes (lavapipe: workgroups / threads each; the remainder goes one by one).
    fn full_per_run(blocks: &[u32], threads: usize, full: u32) -> Vec<usize> {
        let run = blocks.len() / threads;
        blocks.chunks_exact(run).map(|c| c.iter().filter(|&&b| b < full).count()).collect()
    }

    #[test]
    fn spread_is_a_permutation_that_deals_the_first_blocks_out_evenly() {
        let mut shapes: Vec<[u32; 3]> = (1..=3000).map(grid_1d).collect();
        shapes.extend([[65_535, 1, 1], [7, 3, 1], [5, 40, 1], [3, 65_535, 1]]);
        for groups in shapes {
            let blocks = spread_blocks(groups);
            let n = blocks.len();
            let mut seen = vec![false; n];
            for &b in &blocks {
                assert!(!std::mem::replace(&mut seen[b as usize], true), "{groups:?}: {b} twice");
            }
            // With only the first `full` blocks doing work, every run gets close to its share.
            if groups[1] > 1 || n < 64 {
                continue;
            }
            for threads in [2, 3, 4, 8, 16] {
                let run = n / threads;
                for full in [n / 7, n / 3, n / 2, (2 * n) / 3] {
                    let share = (full * run) as f64 / n as f64;
                    for got in full_per_run(&blocks, threads, full as u32) {
                        assert!(
                            (got as f64 - share).abs() <= 0.2 * share + 3.0,
                            "{n} workgroups, {threads} threads, {full} full: {got} in a run, \
                             share {share:.1}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn the_depth_sort_that_ran_on_one_thread_is_shared() {
        // The case that motivated the spread: 13 workgroups over the capacity, 6 full, two
        // threads. In workgroup order the first run held all 6; spread, each holds 2 or 3.
        let blocks = spread_blocks([13, 1, 1]);
        assert_eq!(full_per_run(&(0..13).collect::<Vec<u32>>(), 2, 6), [6, 0]);
        for got in full_per_run(&blocks, 2, 6) {
            assert!(
                (2..=3).contains(&got),
                "{got} of 6 full blocks in one of two runs: {blocks:?}"
            );
        }
    }
}
