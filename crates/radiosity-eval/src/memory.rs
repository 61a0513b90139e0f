//! This process's memory and CPU time: its peak resident size, which the bench sections and
//! each rank of a distributed run report, the CPU seconds its threads have used, which the
//! phase table reports, and how the blocks it frees go back to the system.

/// The high-water mark of this process's resident memory (`VmHWM` of `/proc/self/status`), in
/// bytes; `None` where there is no `/proc`.
pub fn peak_rss() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.trim_start_matches("VmHWM:").trim().trim_end_matches("kB").trim().parse().ok()?;
    Some(kb * 1024)
}

/// The CPU seconds, user and system, that all of this process's threads have used so far
/// (`getrusage`); `None` where the system does not say. Against a phase's wall seconds it
/// tells a part that ran on one thread (CPU ≈ wall) from threads that contend (CPU grows).
pub fn cpu_seconds() -> Option<f64> {
    #[cfg(unix)]
    {
        let mut usage = std::mem::MaybeUninit::<libc::rusage>::zeroed();
        // SAFETY: `getrusage` fills the `rusage` it is given, which is valid for writes; it
        // is read only when the call succeeded.
        #[allow(unsafe_code)]
        let usage = unsafe {
            if libc::getrusage(libc::RUSAGE_SELF, usage.as_mut_ptr()) != 0 {
                return None;
            }
            usage.assume_init()
        };
        let seconds = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
        Some(seconds(usage.ru_utime) + seconds(usage.ru_stime))
    }
    #[cfg(not(unix))]
    None
}

/// Makes every block of 128 KiB or more a mapping of its own, handed back to the system when
/// it is freed. By default glibc raises that threshold each time such a block is freed, up to
/// 32 MiB, so that the blocks a large build frees afterwards stay in its heap, resident to the
/// end of the run, where only smaller blocks can reuse them: a hierarchical operator's links
/// as they were gathered, 0.9 GB at a million patches. Fixing it took that build's peak from
/// 2.33 GB to 1.94 GB and the solve after it from 2.29 GB to about 1.4 GB (docs/scale.md,
/// "Issue 63"). The command line and the Python module call it once, at start; a program of
/// one's own may. It does nothing but on glibc.
pub fn return_freed_blocks() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: `mallopt` sets a parameter of glibc's allocator, which may be set at any time
    // and from any thread; blocks already allocated keep how they were made.
    #[allow(unsafe_code)]
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 128 * 1024);
    }
}
