//! The memory limit of the process's Linux control group, which sysinfo does not read (it
//! looks only at the root group's files).

use std::path::Path;

/// The control group's memory limit: v2 (`/sys/fs/cgroup/<group>/memory.max`) or v1
/// (`/sys/fs/cgroup/memory/<group>/memory.limit_in_bytes`); "max" or a value near `u64::MAX`
/// (v1's "no limit") is none.
pub(super) fn limit() -> Option<u64> {
    let groups = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    candidates(&groups)
        .iter()
        .filter_map(|p| std::fs::read_to_string(p).ok()?.trim().parse::<u64>().ok())
        .filter(|&v| v < (1 << 60))
        .min()
}

/// The limit files named by `/proc/self/cgroup`'s lines.
fn candidates(groups: &str) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    for line in groups.lines() {
        let mut parts = line.splitn(3, ':');
        let (Some(_), Some(controllers), Some(path)) = (parts.next(), parts.next(), parts.next())
        else {
            continue;
        };
        let path = path.trim_start_matches('/');
        if controllers.is_empty() {
            out.push(Path::new("/sys/fs/cgroup").join(path).join("memory.max"));
        } else if controllers.split(',').any(|c| c == "memory") {
            out.push(
                Path::new("/sys/fs/cgroup/memory")
                    .join(path)
                    .join("memory.limit_in_bytes"),
            );
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn v2_and_v1_lines_name_their_limit_files() {
        let got = candidates("0::/user.slice/a\n4:cpu,memory:/b\n5:cpu:/c\nbroken\n");
        let want = [
            "/sys/fs/cgroup/user.slice/a/memory.max",
            "/sys/fs/cgroup/memory/b/memory.limit_in_bytes",
        ];
        assert_eq!(got, want.map(std::path::PathBuf::from));
    }
}
