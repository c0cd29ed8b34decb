//! Work without the GIL, cancelled by Ctrl-C: the work runs on a scoped thread while the
//! calling thread waits for it, looking at Python's signals between waits; a
//! `KeyboardInterrupt` (or any exception a signal handler raises) cancels the render's token
//! and is raised once the work has stopped (within a batch of samples). Short work runs on the
//! calling thread instead ([`run_inline`]): the watcher thread costs more than it saves there.

use aperture_render::Cancel;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use std::sync::mpsc;
use std::time::Duration;

/// How often the waiting thread looks at Python's signals.
const POLL: Duration = Duration::from_millis(25);

/// Runs `work` without the GIL (other Python threads run meanwhile) and returns its result; a
/// signal's exception cancels `cancel` and is returned instead once `work` has returned. A
/// panic in `work` becomes a `RuntimeError`, never a crash.
pub(crate) fn run<T: Send>(
    py: Python<'_>,
    cancel: &Cancel,
    work: impl FnOnce() -> PyResult<T> + Send,
) -> PyResult<T> {
    py.detach(|| {
        std::thread::scope(|s| {
            let (done, wait) = mpsc::channel::<()>();
            let handle = s.spawn(move || {
                let out = work();
                // The waiter may be gone only if it panicked; nothing to tell then.
                let _ = done.send(());
                out
            });
            let mut raised = None;
            while let Err(mpsc::RecvTimeoutError::Timeout) = wait.recv_timeout(POLL) {
                if raised.is_none() {
                    if let Err(e) = Python::attach(|py| py.check_signals()) {
                        cancel.cancel();
                        raised = Some(e);
                    }
                }
            }
            let out = handle
                .join()
                .unwrap_or_else(|_| Err(PyRuntimeError::new_err("aperture: internal panic")));
            match raised {
                Some(e) => Err(e),
                None => out,
            }
        })
    })
}

/// Runs `work` without the GIL on the calling thread, with no thread to watch for signals: for
/// work too short to need cancelling (a signal's exception is raised by Python as soon as the
/// call returns). A panic in `work` becomes a `RuntimeError`, never a crash.
pub(crate) fn run_inline<T: Send>(
    py: Python<'_>,
    work: impl FnOnce() -> PyResult<T> + Send,
) -> PyResult<T> {
    py.detach(|| {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(work))
            .unwrap_or_else(|_| Err(PyRuntimeError::new_err("aperture: internal panic")))
    })
}

/// `work` on a pool of `threads` workers (`None`: rayon's global pool, all cores).
pub(crate) fn with_threads<T: Send>(
    threads: Option<usize>,
    work: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    match threads {
        None => Ok(work()),
        Some(n) => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| PyRuntimeError::new_err(format!("thread pool: {e}")))?;
            Ok(pool.install(work))
        }
    }
}

/// `work(serial)` for a query: on the calling thread for one thread (`serial`: no pool is
/// built), else as [`with_threads`].
pub(crate) fn on_threads<T: Send>(
    threads: Option<usize>,
    work: impl FnOnce(bool) -> T + Send,
) -> PyResult<T> {
    match threads {
        Some(1) => Ok(work(true)),
        _ => with_threads(threads, || work(false)),
    }
}
