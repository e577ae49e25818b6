//! The C allocator (glibc's malloc) tuned for the kind of run: a shift of
//! following, or a batch.
//!
//! **A shift** (`watch`, the TUI, `rig-sim`). Why: an 8-hour follow
//! (BENCHMARKS.md, runs G and I) grew its resident memory by 15–20 % while
//! pinsight's own live data stayed flat (28 MB in use at hour 7 of 40 MB
//! held by glibc). glibc's defaults are made for short programs: its mmap
//! threshold rises each time a large block is freed, so later large blocks
//! come from the heap, where freed room is kept, and each thread's arena
//! keeps its own free room. Fixed thresholds and two arenas (run J, set by
//! environment) held the same shift ~7 MB lower and flat after half an
//! hour. Applied once, when following starts.
//!
//! **A batch** (`inspect`, `yield`, `render`, `batch`, ...). Why: an
//! inspection allocates and frees a few large blocks per image (the decoded
//! frame, the coarse image's passes). Once glibc's threshold has risen they
//! come from the heap, but each time the heap's top is freed beyond the trim
//! threshold glibc gives it back, and the next image faults every page in
//! again: `pinsight yield --jobs 1` over 40 5 MP JPEGs took 126 000 page
//! faults, with these settings 4 000, and 0.81× the time; peak resident
//! memory went from 26 to 30 MB (BENCHMARKS.md, "Cheaper passes"). So a batch
//! keeps [`BATCH_TOP_PAD`] of free room at each heap's top, and takes
//! blocks under [`BATCH_MMAP_THRESHOLD`] from the heap.
//!
//! Only on glibc (musl and other platforms keep their allocator's
//! defaults). A user's own `MALLOC_*` environment variables win: a setting
//! already made by environment is left as it is.

/// Blocks of this size or more get their own mapping, returned to the
/// system when freed (glibc's starting value; fixing it stops it rising).
const MMAP_THRESHOLD: i32 = 128 * 1024;
/// Free room at the top of a heap above this is given back to the system.
const TRIM_THRESHOLD: i32 = 128 * 1024;
/// Arenas: the UI (or `watch`) thread and the follower's thread.
const ARENA_MAX: i32 = 2;

/// Free room kept at the top of each heap in a batch (the largest
/// inspection's working set, a 5 MP frame's, is about 20 MB).
const BATCH_TOP_PAD: i32 = 64 * 1024 * 1024;

/// Blocks under this size come from the heap in a batch: glibc's largest
/// threshold, where its own rising threshold ends (setting the pad stops it
/// rising, so it is fixed here).
const BATCH_MMAP_THRESHOLD: i32 = 32 * 1024 * 1024;

/// Applies the batch settings once per process (later calls do nothing).
pub fn settle_for_a_batch() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(apply_batch);
}

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

/// Sets one of glibc's parameters unless the environment already set it.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn set(env: &str, param: libc::c_int, value: i32) {
    if std::env::var_os(env).is_none() {
        // SAFETY: mallopt takes plain integers; a refused setting
        // returns 0 and leaves glibc's default in place.
        unsafe {
            libc::mallopt(param, value);
        }
    }
}

#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn apply_batch() {
    set(
        "MALLOC_MMAP_THRESHOLD_",
        libc::M_MMAP_THRESHOLD,
        BATCH_MMAP_THRESHOLD,
    );
    set("MALLOC_TOP_PAD_", libc::M_TOP_PAD, BATCH_TOP_PAD);
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn apply_batch() {}

#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn apply() {
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
