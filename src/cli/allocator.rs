//! Allocator settings of the command-line tool (issue 8).
//!
//! On this kind of machine a page touched for the first time is expensive (a fault, then the
//! kernel zeroes it). Two settings of glibc's malloc cut that cost; the library sets neither (a
//! program that embeds it owns its allocator, and can set the same through `GLIBC_TUNABLES`):
//!
//! - **Keep freed memory.** glibc gives freed memory at the top of its heap back to the kernel
//!   as soon as more than 128 KB are free there, and the next stage then faults the same
//!   amount in again. The tool makes one mesh and exits, so it keeps up to 2 GB of what it
//!   freed (`trim_threshold`) and grows its heap 64 MB at a time (`top_pad`): measured on 1e4
//!   and 1e5 bubbles, the system time fell by about a third (1e5: 7.8 -> 4.8 s) at the same
//!   peak memory. Memory still goes back to the kernel at exit. Blocks from 128 KB up were
//!   each a mapping of their own, given back when freed and faulted in again by the next;
//!   the tool keeps blocks up to 32 MiB (`mmap_threshold`, glibc's largest) on its heaps,
//!   where freed memory is reused: 1e5 bubbles fault 1.10 M pages instead of 1.21 M (the
//!   triangulation's and the front end's vectors of a few MB), 6.9-7.2 s against 7.0-8.0 s,
//!   peak 4.11 GB against 4.09 GB; 1e3 and 1e4 are unchanged (their faults already matched
//!   their peak).
//! - **Transparent huge pages**, with `--huge-pages` (`glibc.malloc.hugetlb=1`, where the
//!   kernel gives huge pages on request: `/sys/kernel/mm/transparent_hugepage/enabled` =
//!   `madvise`): malloc asks for 2 MiB pages for its heaps, one fault instead of 512. glibc
//!   reads this setting only when a process starts, so the tool starts itself again (`exec`:
//!   same process id, arguments and standard streams; ~1 ms) with it in `GLIBC_TUNABLES`,
//!   together with the two settings above, and `MEDIAL_BLOCKS_HUGE_PAGES=on` so that it does
//!   so once. Not the default: on this project's virtual machines, whose free 2 MiB blocks
//!   go back to the host (virtio-balloon free page reporting), a huge page is often memory
//!   the host must supply again. Runs back to back gain (1e3 bubbles: `--timings` total ~57
//!   -> ~47 ms, 1e4 ~530 -> ~400 ms), a run after a pause of a few seconds loses (1e3: ~67 ->
//!   ~77 ms median), and so does 1e5 (7.9-8.5 -> 9.0-10.6 s). On a machine that keeps its
//!   memory it may be worth trying.
//!
//! A user who set `GLIBC_TUNABLES`, `MALLOC_TRIM_THRESHOLD_`, `MALLOC_TOP_PAD_` or
//! `MALLOC_MMAP_THRESHOLD_` is left alone. Elsewhere than glibc on Linux nothing happens. The
//! mesh and every file are the same either way (tests/ux_allocator.rs).

/// The environment variable the tool sets to `on` when it starts itself again with huge
/// pages (so that it does so once).
pub const HUGE_PAGES_VAR: &str = "MEDIAL_BLOCKS_HUGE_PAGES";

/// What the tool puts in `GLIBC_TUNABLES` when it starts itself again: huge pages, and the
/// same trim threshold, top pad and mmap threshold as [`keep_freed_memory`]'s `mallopt`
/// calls.
pub const TUNABLES: &str = "glibc.malloc.hugetlb=1:glibc.malloc.trim_threshold=2147483647:\
glibc.malloc.top_pad=67108864:glibc.malloc.mmap_threshold=33554432";

/// Tune malloc for one mesh and an exit: with `huge_pages`, start again with huge pages
/// where the kernel gives them (the call then does not return); else keep freed memory
/// through `mallopt`. Call it before any other thread exists.
pub fn tune(huge_pages: bool) {
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    let _ = huge_pages;
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        if user_tuned() || huge_pages_active() {
            return;
        }
        let wanted =
            huge_pages && std::env::var_os(HUGE_PAGES_VAR).is_none() && kernel_gives_huge_pages();
        if wanted {
            // Only returns on failure (no /proc, exec refused): go on with normal pages.
            let _ = restart_with_tunables();
        }
        keep_freed_memory();
    }
}

/// Whether this process runs with [`TUNABLES`] (it was started again by [`tune`]).
pub fn huge_pages_active() -> bool {
    cfg!(all(target_os = "linux", target_env = "gnu"))
        && std::env::var_os(HUGE_PAGES_VAR).is_some_and(|v| v == "on")
        && std::env::var_os("GLIBC_TUNABLES").is_some_and(|v| v == TUNABLES)
}

/// The user tuned glibc's malloc through its own environment variables (a `GLIBC_TUNABLES`
/// that is not this tool's restart).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn user_tuned() -> bool {
    (std::env::var_os("GLIBC_TUNABLES").is_some() && !huge_pages_active())
        || [
            "MALLOC_TRIM_THRESHOLD_",
            "MALLOC_TOP_PAD_",
            "MALLOC_MMAP_THRESHOLD_",
        ]
        .iter()
        .any(|v| std::env::var_os(v).is_some())
}

/// The kernel gives transparent huge pages to memory that asks for them (`[madvise]`); with
/// `[always]` every heap gets them anyway, with `[never]` none does.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn kernel_gives_huge_pages() -> bool {
    std::fs::read_to_string("/sys/kernel/mm/transparent_hugepage/enabled")
        .is_ok_and(|s| s.contains("[madvise]"))
}

/// `exec` this program again with [`TUNABLES`]; returns only if that failed.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn restart_with_tunables() -> std::io::Error {
    use std::os::unix::process::CommandExt;
    let mut args = std::env::args_os();
    let mut command = std::process::Command::new("/proc/self/exe");
    if let Some(argv0) = args.next() {
        command.arg0(argv0);
    }
    command
        .args(args)
        .env("GLIBC_TUNABLES", TUNABLES)
        .env(HUGE_PAGES_VAR, "on")
        .exec()
}

/// Keep up to 2 GB of freed heap (`M_TRIM_THRESHOLD`), grow the heap 64 MB at a time
/// (`M_TOP_PAD`) and serve blocks up to 32 MiB from the heaps (`M_MMAP_THRESHOLD`, the
/// largest glibc accepts). Only on glibc; elsewhere nothing happens.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn keep_freed_memory() {
    use std::os::raw::c_int;
    extern "C" {
        /// glibc's `mallopt(3)`: returns 1 on success, 0 on error.
        fn mallopt(param: c_int, value: c_int) -> c_int;
    }
    const M_TRIM_THRESHOLD: c_int = -1;
    const M_TOP_PAD: c_int = -2;
    const M_MMAP_THRESHOLD: c_int = -3;
    // SAFETY: mallopt only changes malloc's parameters; it is called before any other
    // thread exists and takes plain integers.
    unsafe {
        mallopt(M_TRIM_THRESHOLD, c_int::MAX);
        mallopt(M_TOP_PAD, 64 << 20);
        mallopt(M_MMAP_THRESHOLD, 32 << 20);
    }
}
