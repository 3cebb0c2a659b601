//! The number of ray queries (closest hit and shadow) each thread has made, a deterministic
//! measure of the work samples do: `--integrator auto` compares integrators by it (their cost
//! per sample), where wall-clock time would make the choice, and so the image, depend on the
//! machine's load. One thread-local counter; a session sums its own worker threads' counters
//! (`rayon::ThreadPool::broadcast`).

use std::cell::Cell;

thread_local! {
    static QUERIES: Cell<u64> = const { Cell::new(0) };
}

/// Counts one ray query on this thread.
#[inline]
pub(crate) fn count() {
    QUERIES.with(|c| c.set(c.get().wrapping_add(1)));
}

/// Ray queries made on this thread so far.
pub fn on_this_thread() -> u64 {
    QUERIES.with(Cell::get)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_per_thread() {
        let before = on_this_thread();
        count();
        count();
        assert_eq!(on_this_thread() - before, 2);
        let other = std::thread::spawn(on_this_thread).join().unwrap();
        assert_eq!(other, 0);
    }
}
