//! The worker threads of a session (a rayon pool of the requested size, all cores by default).

use crate::error::{Error, Result};

/// A thread pool of `threads` workers (at least 1), or one per core.
pub(super) fn new(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        builder = builder.num_threads(n.max(1));
    }
    builder
        .build()
        .map_err(|e| Error::resource(format!("cannot start worker threads: {e}")))
}

/// Ray queries the pool's threads have made so far (`scene::ray_count`, one counter per
/// thread): the same for the same samples on any machine and thread count.
pub(super) fn ray_queries(pool: &rayon::ThreadPool) -> u64 {
    pool.broadcast(|_| crate::scene::ray_count::on_this_thread())
        .into_iter()
        .sum()
}
