//! What the machine has: physical and available memory (sysinfo, on every platform), the
//! control group's memory limit on Linux, free disk space (fs4: statvfs, or
//! `GetDiskFreeSpaceExW` on Windows).

use std::path::Path;
use sysinfo::{MemoryRefreshKind, RefreshKind, System};

#[cfg(target_os = "linux")]
mod cgroup;

/// The machine's memory.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SystemMemory {
    /// Physical memory (`MemTotal` on Linux).
    pub total: u64,
    /// What can be allocated now without swapping (`MemAvailable` on Linux).
    pub available: u64,
    /// The memory limit of the process's control group (v2 `memory.max`, v1
    /// `memory.limit_in_bytes`), when it has one; always `None` off Linux.
    pub cgroup_limit: Option<u64>,
}

impl SystemMemory {
    /// The most a process may hope to use: the physical memory, or the control group's limit
    /// where that is lower.
    pub fn limit(&self) -> u64 {
        self.cgroup_limit.map_or(self.total, |c| c.min(self.total))
    }
}

/// Reads the machine's memory (`None` where the platform does not tell it).
pub fn system_memory() -> Option<SystemMemory> {
    let sys = System::new_with_specifics(
        RefreshKind::nothing().with_memory(MemoryRefreshKind::nothing().with_ram()),
    );
    let total = sys.total_memory();
    if total == 0 {
        return None;
    }
    let available = match sys.available_memory() {
        0 => total,
        a => a.min(total),
    };
    Some(SystemMemory {
        total,
        available,
        cgroup_limit: cgroup_limit(),
    })
}

#[cfg(target_os = "linux")]
fn cgroup_limit() -> Option<u64> {
    cgroup::limit()
}

#[cfg(not(target_os = "linux"))]
fn cgroup_limit() -> Option<u64> {
    None
}

/// Bytes free for an unprivileged user on the file system holding `path` (or its folder, when
/// `path` does not exist yet); `None` when it cannot be read.
pub fn free_disk_bytes(path: &Path) -> Option<u64> {
    let dir = if path.is_dir() {
        path
    } else {
        match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        }
    };
    fs4::available_space(dir).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn this_machine_reports_its_memory_and_disk() {
        let m = system_memory().expect("the machine's memory");
        assert!(m.total > 64 << 20, "{m:?}");
        assert!(m.available <= m.total, "{m:?}");
        assert!(m.limit() <= m.total);
        let free = free_disk_bytes(&std::env::temp_dir().join("no-such-file")).expect("free disk");
        assert!(free > 0);
    }

    /// The total agrees with `/proc/meminfo`'s, which the budget read itself before sysinfo.
    #[cfg(target_os = "linux")]
    #[test]
    fn the_total_is_meminfos() {
        let info = std::fs::read_to_string("/proc/meminfo").expect("/proc/meminfo");
        let line = info
            .lines()
            .find(|l| l.starts_with("MemTotal:"))
            .expect("MemTotal");
        let kb: u64 = line["MemTotal:".len()..]
            .trim()
            .trim_end_matches("kB")
            .trim()
            .parse()
            .expect("a number");
        assert_eq!(system_memory().expect("memory").total, kb * 1024);
    }
}
