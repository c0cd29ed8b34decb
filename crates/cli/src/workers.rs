//! The worker threads the rendering commands run on.

use anyhow::Context as _;

/// A pool of `threads` workers (`None`: one per core), as `--threads` asks.
pub(crate) fn worker_pool(threads: Option<u32>) -> anyhow::Result<rayon::ThreadPool> {
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(t) = threads {
        pool = pool.num_threads(t as usize);
    }
    pool.build().context("starting worker threads")
}
