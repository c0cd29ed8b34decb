//! What the machine has: memory from `/proc/meminfo` and the control group, free disk space
//! from `statvfs`.

use std::path::Path;

/// The machine's memory as Linux reports it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SystemMemory {
    /// `MemTotal`: physical memory.
    pub total: u64,
    /// `MemAvailable`: what can be allocated now without swapping.
    pub available: u64,
    /// The memory limit of the process's control group (v2 `memory.max`, v1
    /// `memory.limit_in_bytes`), when it has one.
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

/// Reads the machine's memory (`None` where `/proc/meminfo` cannot be read: not Linux).
pub fn system_memory() -> Option<SystemMemory> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let field = |name: &str| kb_field(&info, name);
    let total = field("MemTotal:")?;
    Some(SystemMemory {
        total,
        available: field("MemAvailable:").unwrap_or(total),
        cgroup_limit: cgroup_limit(),
    })
}

/// The control group's memory limit: v2 (`/sys/fs/cgroup/<group>/memory.max`) or v1
/// (`/sys/fs/cgroup/memory/<group>/memory.limit_in_bytes`); "max" or a value near `u64::MAX`
/// (v1's "no limit") is none.
fn cgroup_limit() -> Option<u64> {
    let groups = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let mut candidates = Vec::new();
    for line in groups.lines() {
        let mut parts = line.splitn(3, ':');
        let (_, controllers, path) = (parts.next()?, parts.next()?, parts.next()?);
        let path = path.trim_start_matches('/');
        if controllers.is_empty() {
            candidates.push(Path::new("/sys/fs/cgroup").join(path).join("memory.max"));
        } else if controllers.split(',').any(|c| c == "memory") {
            candidates.push(
                Path::new("/sys/fs/cgroup/memory")
                    .join(path)
                    .join("memory.limit_in_bytes"),
            );
        }
    }
    candidates
        .iter()
        .filter_map(|p| std::fs::read_to_string(p).ok()?.trim().parse::<u64>().ok())
        .filter(|&v| v < (1 << 60))
        .min()
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
    let s = rustix::fs::statvfs(dir).ok()?;
    s.f_bavail.checked_mul(s.f_frsize)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn this_machine_reports_its_memory_and_disk() {
        if !cfg!(target_os = "linux") {
            return;
        }
        let m = system_memory().expect("/proc/meminfo");
        assert!(m.total > 64 << 20, "{m:?}");
        assert!(m.available <= m.total, "{m:?}");
        assert!(m.limit() <= m.total);
        let free = free_disk_bytes(&std::env::temp_dir().join("no-such-file")).expect("statvfs");
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
}
