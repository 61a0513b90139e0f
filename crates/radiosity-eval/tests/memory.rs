//! Blocks of a mebibyte freed after `return_freed_blocks` go back to the system, even where
//! glibc's default would keep them: after a block of that size was freed once, and with a
//! small block allocated after them, so that the heap's top cannot be trimmed.

/// This process's resident memory, in bytes (`VmRSS`).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn resident() -> usize {
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    let line = status.lines().find(|l| l.starts_with("VmRSS:")).unwrap();
    let kb: usize = line.trim_start_matches("VmRSS:").trim().trim_end_matches("kB").trim().parse().unwrap();
    kb * 1024
}

#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[test]
fn freed_blocks_of_a_mebibyte_leave_the_process() {
    use std::hint::black_box;
    const BLOCKS: usize = 96;
    const MIB: usize = 1 << 20;
    radiosity_eval::return_freed_blocks();
    // By default this free raises glibc's threshold above a mebibyte, so that the blocks
    // below would come from the heap.
    drop(black_box(vec![1u8; MIB]));
    let blocks: Vec<Vec<u8>> = (0..BLOCKS).map(|i| black_box(vec![i as u8 + 1; MIB])).collect();
    let pin = black_box(vec![1u8; 64]);
    let before = resident();
    drop(blocks);
    let after = resident();
    let returned = before.saturating_sub(after);
    assert!(
        returned >= BLOCKS * MIB * 3 / 4,
        "{} MiB of {BLOCKS} freed went back ({} MiB resident before, {} after)",
        returned / MIB,
        before / MIB,
        after / MIB
    );
    drop(pin);
}
