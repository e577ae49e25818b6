//! The shift settings of the C allocator (`allocator`), in a process
//! of their own: glibc's counters are process-wide, so no other test may
//! allocate while this one reads them.

/// After the settings, a large block freed no longer raises glibc's mmap
/// threshold: a later large block still gets a mapping of its own, whose
/// memory goes back to the system when it is freed. Without the settings
/// glibc raises the threshold to 1 MB at the first free and the 512 kB
/// block comes from the heap (the test fails).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[test]
fn large_blocks_stay_mapped_after_large_frees() {
    if std::env::var_os("MALLOC_MMAP_THRESHOLD_").is_some() {
        eprintln!("MALLOC_MMAP_THRESHOLD_ is set by environment: skipped");
        return;
    }
    pinsight::allocator::settle_for_a_shift();
    drop(std::hint::black_box(vec![1u8; 1 << 20]));
    // SAFETY: mallinfo2 only reads glibc's counters.
    let before = unsafe { libc::mallinfo2() }.hblkhd;
    let v = std::hint::black_box(vec![2u8; 512 * 1024]);
    let during = unsafe { libc::mallinfo2() }.hblkhd;
    drop(v);
    let after = unsafe { libc::mallinfo2() }.hblkhd;
    assert!(
        during >= before + 512 * 1024,
        "a 512 kB block after a 1 MB free was not mapped on its own: \
         mapped {before} -> {during} bytes"
    );
    assert!(
        after < during,
        "the freed block stayed mapped: {after} bytes"
    );
    pinsight::allocator::give_back_free_room();
}
