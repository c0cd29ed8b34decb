//! `keep_freed_memory`: memory freed and allocated again is not faulted in again.

/// Minor page faults of the calling thread so far (`/proc/thread-self/stat`, field 10).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn thread_minor_faults() -> u64 {
    let stat = std::fs::read_to_string("/proc/thread-self/stat").expect("thread stat");
    // The command name (field 2) is in brackets and may hold spaces: count after it.
    let rest = &stat[stat.rfind(')').expect("a command name") + 2..];
    rest.split(' ')
        .nth(7)
        .expect("field 10")
        .parse()
        .expect("a count")
}

/// Sixteen 4 MiB blocks written through, then freed.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn touch_blocks() -> u64 {
    let before = thread_minor_faults();
    let blocks: Vec<Vec<u8>> = (0..16u8).map(|i| vec![i | 1; 4 << 20]).collect();
    assert!(blocks.iter().all(|b| b[b.len() - 1] != 0));
    drop(blocks);
    thread_minor_faults() - before
}

#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[test]
fn freed_blocks_are_reused_without_new_faults() {
    aperture_budget::keep_freed_memory();
    let first = touch_blocks();
    let second = touch_blocks();
    // 64 MiB is 16,384 pages: the first round faults them in, the second reuses them.
    assert!(first >= 8_000, "first round: {first} faults");
    assert!(second * 8 < first, "{second} faults again after {first}");
}
