//! Independent items of CPU work spread over the cores: one contiguous chunk of items per core, in
//! scoped threads. Each item's result depends only on the item, never on the split.

/// Runs `work(i, &mut items[i])` for every item and reports each item done to `progress`
/// (done, total) from the calling thread, as the workers finish them.
pub fn for_each_item<T: Send>(
    items: &mut [T],
    progress: &mut dyn FnMut(usize, usize),
    work: impl Fn(usize, &mut T) + Sync,
) {
    let n = items.len();
    let threads = std::thread::available_parallelism().map_or(1, |t| t.get()).min(n.max(1));
    let per = n.div_ceil(threads).max(1);
    let (done_tx, done_rx) = std::sync::mpsc::channel::<()>();
    std::thread::scope(|scope| {
        for (t, chunk) in items.chunks_mut(per).enumerate() {
            let (work, done_tx) = (&work, done_tx.clone());
            scope.spawn(move || {
                for (k, item) in chunk.iter_mut().enumerate() {
                    work(t * per + k, item);
                    let _ = done_tx.send(());
                }
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
}
