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

/// The bytes of the `name` line (`"MemTotal:"`, `"VmHWM:"`) of a `/proc` file that counts in
/// kB, as `/proc/meminfo` and `/proc/self/status` do.
fn kb_field(text: &str, name: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(name))?;
    let kb: u64 = line[name.len()..]
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    kb.checked_mul(1024)
}

/// The most resident memory this process has held so far (`VmHWM` of `/proc/self/status`), in
/// bytes; `None` where that cannot be read (not Linux).
pub fn peak_resident_bytes() -> Option<u64> {
    peak_in_status(&std::fs::read_to_string("/proc/self/status").ok()?)
}

/// `VmHWM` of a `/proc/<pid>/status` text, in bytes.
fn peak_in_status(status: &str) -> Option<u64> {
    kb_field(status, "VmHWM:")
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

    #[test]
    fn the_peak_is_read_from_vmhwm() {
        let status = "Name:\taperture\nVmPeak:\t  900 kB\nVmHWM:\t   1234 kB\nVmRSS:\t 1000 kB\n";
        assert_eq!(peak_in_status(status), Some(1234 * 1024));
        assert_eq!(peak_in_status("Name:\taperture\n"), None);
        assert_eq!(peak_in_status("VmHWM:\t lots kB\n"), None);
        if cfg!(target_os = "linux") {
            // This process holds at least the 64 MB it just touched.
            let held = vec![1u8; 64 << 20];
            let peak = peak_resident_bytes().expect("/proc/self/status");
            assert!(peak >= 64 << 20, "{peak}");
            assert_eq!(held.iter().map(|&b| u64::from(b)).sum::<u64>(), 64 << 20);
        }
    }

    /// The total agrees with `/proc/meminfo`'s, which the budget read itself before sysinfo.
    #[cfg(target_os = "linux")]
    #[test]
    fn the_total_is_meminfos() {
        let info = std::fs::read_to_string("/proc/meminfo").expect("/proc/meminfo");
        let total = kb_field(&info, "MemTotal:").expect("MemTotal");
        assert_eq!(system_memory().expect("memory").total, total);
    }
}
