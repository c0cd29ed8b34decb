//! Budgets checked before allocating: how much memory the machine (or the control group the
//! process runs in) has, how much disk the output's file system has free, and sizes said in
//! words ("137.4 GB").
//!
//! A renderer that finds out it is too big by being killed an hour in wastes that hour. Every
//! large allocation of the scene loader and the renderer is sized first and compared with a
//! [`MemoryBudget`]: the machine's memory by default, or what the user gives (`--max-memory`).
//!
//! ```
//! use aperture_budget::{MemoryBudget, human_bytes};
//! let budget = MemoryBudget::fixed(8 << 30);
//! assert!(budget.check("the film", 137_438_953_472).is_err());
//! assert_eq!(human_bytes(137_438_953_472), "137.4 GB");
//! ```
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

mod allocator;
mod parse;
mod system;

pub use allocator::keep_freed_memory;
pub use parse::parse_bytes;
pub use system::{free_disk_bytes, peak_resident_bytes, system_memory, SystemMemory};

/// Where a budget's limit comes from, for messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LimitSource {
    /// The machine's physical memory (`MemTotal`).
    Machine,
    /// A control group's memory limit, lower than the machine's memory.
    ControlGroup,
    /// Given by the user (`--max-memory`) or a caller.
    Given,
}

impl std::fmt::Display for LimitSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            LimitSource::Machine => "this machine has",
            LimitSource::ControlGroup => "this process's control group may use",
            LimitSource::Given => "the memory limit (--max-memory) is",
        })
    }
}

/// A job's memory did not fit.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{what} needs {} but {limit_source} {}{hint}", human_bytes(*.needed), human_bytes(*.limit))]
pub struct OverBudget {
    /// What was to be allocated ("a 65536x65536 PNG render").
    pub what: String,
    /// Bytes it needs.
    pub needed: u64,
    /// Bytes the budget allows.
    pub limit: u64,
    /// Where the limit comes from.
    pub limit_source: LimitSource,
    /// Advice appended to the message (may be empty).
    pub hint: String,
}

/// The most memory a job may use, and where that number comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MemoryBudget {
    /// Bytes.
    pub limit: u64,
    /// Where the limit comes from.
    pub source: LimitSource,
}

impl MemoryBudget {
    /// The machine's memory, or its control group's limit where that is lower; `u64::MAX`
    /// (no limit) where neither can be read (not Linux).
    pub fn from_system() -> Self {
        match system_memory() {
            Some(m) => Self {
                limit: m.limit(),
                source: if m.cgroup_limit.is_some_and(|c| c < m.total) {
                    LimitSource::ControlGroup
                } else {
                    LimitSource::Machine
                },
            },
            None => Self::unlimited(),
        }
    }

    /// A limit given by the user or a caller.
    pub fn fixed(limit: u64) -> Self {
        Self {
            limit,
            source: LimitSource::Given,
        }
    }

    /// No limit.
    pub fn unlimited() -> Self {
        Self {
            limit: u64::MAX,
            source: LimitSource::Given,
        }
    }

    /// `Ok` when `needed` bytes fit, else an error naming `what`, the size and the limit.
    pub fn check(&self, what: &str, needed: u64) -> Result<(), OverBudget> {
        self.check_with_hint(what, needed, "")
    }

    /// [`MemoryBudget::check`] with advice appended to the error message.
    pub fn check_with_hint(&self, what: &str, needed: u64, hint: &str) -> Result<(), OverBudget> {
        if needed <= self.limit {
            return Ok(());
        }
        Err(OverBudget {
            what: what.to_owned(),
            needed,
            limit: self.limit,
            limit_source: self.source,
            hint: hint.to_owned(),
        })
    }
}

impl Default for MemoryBudget {
    /// [`MemoryBudget::from_system`].
    fn default() -> Self {
        Self::from_system()
    }
}

/// A byte count for people: decimal units with one decimal ("137.4 GB", "512 B").
pub fn human_bytes(bytes: u64) -> String {
    const UNITS: [&str; 6] = ["kB", "MB", "GB", "TB", "PB", "EB"];
    if bytes < 1000 {
        return format!("{bytes} B");
    }
    let mut v = bytes as f64 / 1000.0;
    let mut unit = 0;
    while v >= 999.95 && unit + 1 < UNITS.len() {
        v /= 1000.0;
        unit += 1;
    }
    format!("{v:.1} {}", UNITS[unit])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_read_as_people_write_them() {
        assert_eq!(human_bytes(0), "0 B");
        assert_eq!(human_bytes(999), "999 B");
        assert_eq!(human_bytes(1000), "1.0 kB");
        assert_eq!(human_bytes(23_400_000_000), "23.4 GB");
        assert_eq!(human_bytes(999_960_000), "1.0 GB");
        assert_eq!(human_bytes(u64::MAX), "18.4 EB");
    }

    #[test]
    fn over_budget_says_what_how_much_and_the_limit() {
        let b = MemoryBudget {
            limit: 23_000_000_000,
            source: LimitSource::Machine,
        };
        assert!(b.check("x", 23_000_000_000).is_ok());
        let e = b
            .check_with_hint("a 65536x65536 PNG render", 137_000_000_000, "; render EXR")
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "a 65536x65536 PNG render needs 137.0 GB but this machine has 23.0 GB; render EXR"
        );
        let e = MemoryBudget::fixed(1 << 20)
            .check("t", 2 << 20)
            .unwrap_err();
        assert!(e.to_string().contains("--max-memory"), "{e}");
    }
}
