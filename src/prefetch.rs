//! Software prefetch hints for the serial loops that chase indices into large arrays
//! (issue 8). A prefetch never faults and never changes a result, whatever the address.

/// Ask for the cache line at `p` (no-op off x86-64).
#[inline(always)]
pub fn read<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch never faults, whatever the address.
    unsafe {
        std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(p.cast())
    };
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}
