//! The C allocator tuned for a whole shift of following.
//!
//! Why: an 8-hour follow (BENCHMARKS.md, runs G and I) grew its resident
//! memory by 15–20 % while pinsight's own live data stayed flat (28 MB in
//! use at hour 7 of 40 MB held by glibc). glibc's defaults are made for
//! short programs: its mmap threshold rises each time a large block is
//! freed, so later large blocks come from the heap, where freed room is
//! kept, and each thread's arena keeps its own free room. Fixed thresholds
//! and two arenas (run J, set by environment) held the same shift ~7 MB
//! lower and flat after half an hour.
//!
//! The settings are applied once, when following starts, and only on
//! glibc (musl and other platforms keep their allocator's defaults). A
//! user's own `MALLOC_*` environment variables win: a threshold already
//! set by environment is left as it is.

/// Blocks of this size or more get their own mapping, returned to the
/// system when freed (glibc's starting value; fixing it stops it rising).
const MMAP_THRESHOLD: i32 = 128 * 1024;
/// Free room at the top of a heap above this is given back to the system.
const TRIM_THRESHOLD: i32 = 128 * 1024;
/// Arenas: the UI (or `watch`) thread and the follower's thread.
const ARENA_MAX: i32 = 2;

/// Applies the shift settings once per process (later calls do nothing).
pub fn settle_for_a_shift() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(apply);
}

/// Gives free room inside the heaps back to the system (a no-op where the
/// allocator is not glibc). The follower calls it once a minute.
pub fn give_back_free_room() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only walks glibc's own free lists under its locks.
    unsafe {
        libc::malloc_trim(0);
    }
}

#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn apply() {
    let set = |env: &str, param: libc::c_int, value: i32| {
        if std::env::var_os(env).is_none() {
            // SAFETY: mallopt takes plain integers; a refused setting
            // returns 0 and leaves glibc's default in place.
            unsafe {
                libc::mallopt(param, value);
            }
        }
    };
    set(
        "MALLOC_MMAP_THRESHOLD_",
        libc::M_MMAP_THRESHOLD,
        MMAP_THRESHOLD,
    );
    set(
        "MALLOC_TRIM_THRESHOLD_",
        libc::M_TRIM_THRESHOLD,
        TRIM_THRESHOLD,
    );
    set("MALLOC_ARENA_MAX", libc::M_ARENA_MAX, ARENA_MAX);
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn apply() {}

// The test is tests/allocator.rs: alone in its process, so no other test
// frees mapped blocks while it counts them.
