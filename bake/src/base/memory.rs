//! The process's memory: its peak as the system counts it, and handing freed memory back.

/// Peak resident set size of this process (`VmHWM` of `/proc/self/status`), if known.
pub fn peak_rss_bytes() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line
        .trim_start_matches("VmHWM:")
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kb * 1024)
}

/// Hands the allocator's free memory back to the system (glibc's `malloc_trim`). The blocked
/// bake frees large working sets between its phases (the weld's tables once the mesh is
/// stored, a level's block builds, the writer's tables before the written file is
/// validated); glibc keeps the freed blocks under its mapping threshold resident in its
/// heaps, where they would count in each later phase's peak.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
pub fn release_freed() {
    extern "C" {
        fn malloc_trim(pad: usize) -> i32;
    }
    // SAFETY: `malloc_trim` takes glibc's allocator locks and only returns free memory to
    // the system; no memory in use moves.
    unsafe {
        malloc_trim(0);
    }
}

/// Other allocators are left as they are.
#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
pub fn release_freed() {}
