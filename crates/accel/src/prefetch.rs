//! A cache hint for walks bound by dependent misses (the collapse of a binary tree).
//!
//! `aperture-shading` keeps the same ten lines for its hit prefetch: the two crates share no
//! crate of ours below them, and a dependency for one hint is not worth its arrow.

/// Asks the cache for the line holding `p`: a hint, never a read, so any address is sound.
#[inline(always)]
pub(crate) fn prefetch<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch is only a hint: it neither faults nor reads the address into the
    // program, so any pointer value, even out of bounds, is sound.
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        _mm_prefetch::<_MM_HINT_T0>(p as *const i8);
    }
    #[cfg(target_arch = "aarch64")]
    // SAFETY: `prfm` is only a hint, as above: it neither faults nor reads into the program
    // (`std::arch::aarch64::_prefetch` is not stable yet). No memory is written, no flags.
    unsafe {
        std::arch::asm!("prfm pldl1keep, [{p}]", p = in(reg) p, options(nostack, readonly, preserves_flags));
    }
    #[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
    let _ = p;
}
