//! Independent items of CPU work spread over the cores, in scoped threads: each thread takes the
//! next item not yet taken, so that a core that drew light items takes more (the views of a
//! removal differ several-fold in their holes' work). Each item's result depends only on the
//! item, never on which thread worked on it.

use std::sync::Mutex;

/// Runs `work(i, &mut items[i])` for every item and reports each item done to `progress`
/// (done, total) from the calling thread, as the workers finish them.
pub fn for_each_item<T: Send>(
    items: &mut [T],
    progress: &mut dyn FnMut(usize, usize),
    work: impl Fn(usize, &mut T) + Sync,
) {
    let n = items.len();
    let threads = std::thread::available_parallelism().map_or(1, |t| t.get()).min(n.max(1));
    // the items not yet taken, in order; a worker holds the lock only to take one
    let queue = Mutex::new(items.iter_mut().enumerate());
    let (done_tx, done_rx) = std::sync::mpsc::channel::<()>();
    std::thread::scope(|scope| {
        for _ in 0..threads {
            let (work, queue, done_tx) = (&work, &queue, done_tx.clone());
            scope.spawn(move || loop {
                let Some((i, item)) = queue.lock().ok().and_then(|mut q| q.next()) else { break };
                work(i, item);
                let _ = done_tx.send(());
            });
        }
        drop(done_tx);
        for done in 1..=n {
            if done_rx.recv().is_err() {
                break; // a worker panicked; the scope re-raises it
            }
            progress(done, n);
        }
    });
}

#[cfg(test)]
mod tests {
    /// Every item is worked on once with its own index, and progress counts up to the total.
    #[test]
    fn every_item_once_with_its_index_and_progress_to_the_total() {
        for n in [0usize, 1, 7, 100] {
            let mut items: Vec<(usize, u32)> = vec![(usize::MAX, 0); n];
            let mut reports = Vec::new();
            super::for_each_item(&mut items, &mut |d, t| reports.push((d, t)), |i, item| {
                item.0 = i;
                item.1 += 1;
            });
            assert!(items.iter().enumerate().all(|(i, &(j, c))| i == j && c == 1), "{items:?}");
            assert_eq!(reports, (1..=n).map(|d| (d, n)).collect::<Vec<_>>());
        }
    }

    /// The first item waits until every other item is done: with the items split into one
    /// contiguous chunk per core its own thread would owe it half of them, and it would give up
    /// waiting after 10 s with them undone.
    #[test]
    fn a_slow_item_does_not_hold_back_the_items_after_it() {
        use std::sync::atomic::{AtomicUsize, Ordering};
        if std::thread::available_parallelism().map_or(1, |t| t.get()) < 2 {
            return; // one core: nothing to spread
        }
        let n = 20;
        let others_done = AtomicUsize::new(0);
        let mut saw_all = vec![false; n];
        super::for_each_item(&mut saw_all, &mut |_, _| {}, |i, saw| {
            if i == 0 {
                let start = std::time::Instant::now();
                while others_done.load(Ordering::SeqCst) < n - 1 && start.elapsed().as_secs() < 10 {
                    std::thread::sleep(std::time::Duration::from_millis(1));
                }
                *saw = others_done.load(Ordering::SeqCst) == n - 1;
            } else {
                others_done.fetch_add(1, Ordering::SeqCst);
            }
        });
        assert!(saw_all[0], "the items after the first waited for its thread");
    }
}
