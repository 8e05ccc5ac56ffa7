//! A hint to the processor to start loading memory that a step will read soon, for the
//! build's loops over data spread across the whole mesh, which would otherwise wait for
//! each cache miss in turn.

/// Asks the processor to start loading `x`'s cache line for a read soon: a hint, which
/// changes no result.
#[inline(always)]
pub(super) fn prefetch<T>(x: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        // SAFETY: a prefetch never faults and writes nothing; the address is a reference's.
        unsafe { _mm_prefetch::<_MM_HINT_T0>((x as *const T).cast::<i8>()) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
}
