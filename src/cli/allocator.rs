//! Allocator settings of the command-line tool (issue 8).
//!
//! On this kind of machine a page touched for the first time is expensive (a fault, then the
//! kernel zeroes it): at 1e5 particles the mesher spent 8 of its 36 CPU seconds in the kernel.
//! glibc gives freed memory at the top of its heap back to the kernel as soon as more than
//! 128 KB are free there, and the next stage then faults the same amount in again. The tool
//! makes one mesh and exits, so it keeps what it freed instead: measured on 1e4 and 1e5
//! bubbles, the system time falls by about a third (1e5: 7.8 -> 4.8 s) at the same peak
//! memory. Memory still goes back to the kernel at exit. The library does not do this: a
//! program that embeds it owns its allocator.

/// Keep up to 2 GB of freed heap (`M_TRIM_THRESHOLD`) and grow the heap 64 MB at a time
/// (`M_TOP_PAD`), unless the user tuned glibc's malloc through its environment variables.
/// Only on glibc; elsewhere nothing happens.
pub fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        use std::os::raw::c_int;
        extern "C" {
            /// glibc's `mallopt(3)`: returns 1 on success, 0 on error.
            fn mallopt(param: c_int, value: c_int) -> c_int;
        }
        const M_TRIM_THRESHOLD: c_int = -1;
        const M_TOP_PAD: c_int = -2;
        let tuned = [
            "MALLOC_TRIM_THRESHOLD_",
            "MALLOC_TOP_PAD_",
            "GLIBC_TUNABLES",
        ]
        .iter()
        .any(|v| std::env::var_os(v).is_some());
        if !tuned {
            // SAFETY: mallopt only changes malloc's parameters; it is called before any
            // other thread exists and takes plain integers.
            unsafe {
                mallopt(M_TRIM_THRESHOLD, c_int::MAX);
                mallopt(M_TOP_PAD, 64 << 20);
            }
        }
    }
}
