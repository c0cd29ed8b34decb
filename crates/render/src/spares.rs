//! Buffers kept for reuse by the threads of one render, so that a tile does not allocate (and
//! page-fault) what the previous tile already had: wavefronts and a tile's accumulators.

use std::sync::{Mutex, MutexGuard, PoisonError};

/// Spare values for the threads of one render.
pub(crate) struct Spares<T>(Mutex<Vec<T>>);

impl<T> Default for Spares<T> {
    fn default() -> Self {
        Self(Mutex::new(Vec::new()))
    }
}

impl<T> Spares<T> {
    /// A spare value, if any.
    pub fn take(&self) -> Option<T> {
        lock(&self.0).pop()
    }

    /// Keeps `v` for a later [`Spares::take`].
    pub fn give(&self, v: T) {
        lock(&self.0).push(v);
    }
}

/// `m` locked. A lock poisoned by a panicking thread still holds valid data (whole buffers,
/// whole tiles), so it is used as it is.
pub(crate) fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}
