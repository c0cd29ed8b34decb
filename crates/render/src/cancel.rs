//! Stopping a render early: a flag the render loop checks between batches of samples.
//!
//! The command line sets it from SIGINT (Ctrl-C); a library user from anywhere. A cancelled
//! render returns promptly (each worker finishes the batch of at most 64 samples it is on) with
//! the samples taken so far, and every pixel's count says how many that is.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A cancellation flag shared by whoever may stop a render and the render itself. The default
/// token is never cancelled.
///
/// Two tokens always compare equal: cancellation is not part of what is rendered.
#[derive(Clone, Default)]
pub struct Cancel(Option<Arc<AtomicBool>>);

impl Cancel {
    /// A token that [`Cancel::cancel`] (or setting `flag`) cancels.
    pub fn from_flag(flag: Arc<AtomicBool>) -> Self {
        Self(Some(flag))
    }

    /// A new token, not cancelled.
    pub fn new() -> Self {
        Self::from_flag(Arc::new(AtomicBool::new(false)))
    }

    /// Asks the render to stop (a no-op on the default token).
    pub fn cancel(&self) {
        if let Some(f) = &self.0 {
            f.store(true, Ordering::Relaxed);
        }
    }

    /// True once cancelled.
    #[inline]
    pub fn is_cancelled(&self) -> bool {
        self.0.as_ref().is_some_and(|f| f.load(Ordering::Relaxed))
    }
}

impl PartialEq for Cancel {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl std::fmt::Debug for Cancel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Cancel({})", self.is_cancelled())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_share_their_flag() {
        let a = Cancel::new();
        let b = a.clone();
        assert!(!b.is_cancelled());
        a.cancel();
        assert!(b.is_cancelled());
        let never = Cancel::default();
        never.cancel();
        assert!(!never.is_cancelled());
        assert_eq!(a, never);
    }
}
