//! The peak resident memory of this process, which the bench sections and each rank of a
//! distributed run report.

/// The high-water mark of this process's resident memory (`VmHWM` of `/proc/self/status`), in
/// bytes; `None` where there is no `/proc`.
pub fn peak_rss() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.trim_start_matches("VmHWM:").trim().trim_end_matches("kB").trim().parse().ok()?;
    Some(kb * 1024)
}
