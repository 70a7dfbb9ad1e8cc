//! Jobs spread over threads: the per-view work (tracing the synthetic views, loading photos,
//! costing a plane against every view's mask) where each view is a pure function of its index,
//! and the rows of an image filter.
use std::sync::atomic::{AtomicUsize, Ordering};

/// Call `f(i)` for every `i` in `0..n` on up to `max_threads` threads (never more than the
/// cores), each thread taking the next index when it is done, so that uneven jobs balance.
/// When `f` returns false the threads take no further index (the ones already taken finish). A
/// panic in `f` is resumed on the caller's thread.
pub fn for_each_index(n: usize, max_threads: usize, f: impl Fn(usize) -> bool + Sync) {
    let threads = cores().min(max_threads).min(n).max(1);
    let next = AtomicUsize::new(0);
    let worker = || {
        loop {
            let i = next.fetch_add(1, Ordering::Relaxed);
            if i >= n {
                return;
            }
            if !f(i) {
                next.store(n, Ordering::Relaxed);
            }
        }
    };
    std::thread::scope(|scope| {
        let handles: Vec<_> = (0..threads).map(|_| scope.spawn(worker)).collect();
        for handle in handles {
            handle.join().unwrap_or_else(|e| std::panic::resume_unwind(e));
        }
    });
}

/// `f` of every item, in order, computed on all cores (contiguous runs of items per thread).
pub fn map_in_order<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let threads = cores();
    let per_thread = items.len().div_ceil(threads).max(1);
    let f = &f;
    std::thread::scope(|scope| {
        let handles: Vec<_> = items
            .chunks(per_thread)
            .map(|run| scope.spawn(move || run.iter().map(f).collect::<Vec<R>>()))
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            .collect()
    })
}

/// The cores this process may use (1 when that cannot be known).
fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |t| t.get())
}

/// Rows per thread when `rows` rows are split evenly over the cores.
pub fn rows_per_thread(rows: usize) -> usize {
    let threads = cores();
    rows.div_ceil(threads).max(1)
}

/// Call `f(first_row, run)` for runs of `rows_per_run` rows of `data` (rows of `row_len` items;
/// the last run, and its last row, may be shorter), each run on its own thread. A panic in `f`
/// is resumed on the caller's thread.
pub fn for_each_run_mut<T: Send>(
    data: &mut [T],
    row_len: usize,
    rows_per_run: usize,
    f: impl Fn(usize, &mut [T]) + Sync,
) {
    let step = rows_per_run.max(1);
    let f = &f;
    std::thread::scope(|scope| {
        let handles: Vec<_> = data
            .chunks_mut(step * row_len.max(1))
            .enumerate()
            .map(|(t, run)| scope.spawn(move || f(t * step, run)))
            .collect();
        for handle in handles {
            handle.join().unwrap_or_else(|e| std::panic::resume_unwind(e));
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    #[test]
    fn every_index_once_and_a_stop_stops_taking() {
        let seen = Mutex::new(Vec::new());
        for_each_index(100, 4, |i| {
            seen.lock().expect("not poisoned").push(i);
            true
        });
        let mut seen = seen.into_inner().expect("not poisoned");
        seen.sort_unstable();
        assert_eq!(seen, (0..100).collect::<Vec<_>>());
        let taken = AtomicUsize::new(0);
        for_each_index(1000, 4, |i| {
            taken.fetch_add(1, Ordering::Relaxed);
            i != 3
        });
        // Index 3 stops the others: at most one index per thread after it.
        assert!(taken.load(Ordering::Relaxed) < 20, "{}", taken.load(Ordering::Relaxed));
        for_each_index(0, 4, |_| panic!("no index"));
    }

    #[test]
    fn runs_cover_every_row_once_with_their_first_index() {
        let mut data = vec![0usize; 1003];
        for_each_run_mut(&mut data, 10, 7, |first, run| {
            assert_eq!(first % 7, 0);
            assert!(run.len() == 70 || (first == 98 && run.len() == 23), "{first}: {}", run.len());
            run.iter_mut().enumerate().for_each(|(i, v)| *v = first * 10 + i);
        });
        assert_eq!(data, (0..1003).collect::<Vec<_>>());
        for_each_run_mut(&mut Vec::<u8>::new(), 4, 2, |_, _| panic!("no run"));
        assert_eq!(rows_per_thread(0), 1);
        for rows in [1, 7, 1000] {
            let per = rows_per_thread(rows);
            assert!(per <= rows && per * cores() >= rows, "{rows} rows: {per} per thread");
        }
    }

    #[test]
    fn mapped_in_order() {
        let items: Vec<u64> = (0..1001).collect();
        assert_eq!(
            map_in_order(&items, |&i| i * i),
            items.iter().map(|i| i * i).collect::<Vec<_>>()
        );
        assert!(map_in_order(&[] as &[u8], |&b| b).is_empty());
    }
}
