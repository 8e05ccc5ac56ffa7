//! A cache hint for the refinement pass: bring the bounds a visit will read into the nearest
//! cache a few visits ahead.
//!
//! The visits of a pass are independent, but each decision waits for its node's bounds, and
//! with several cameras those come from the last-level cache. Two ways to ask early:
//!
//! - **The prefetch instruction** (`prefetcht0`), with the `prefetch` feature (on by default)
//!   on x86-64. It is a hint: it never faults, writes nothing and retires at once, so the
//!   pass runs on while the line arrives. It is the crate's only `unsafe` (the intrinsic is
//!   declared with `#[target_feature(enable = "sse")]`, which makes every call `unsafe`,
//!   although SSE is part of the x86-64 baseline). Without the feature the crate
//!   `#![forbid(unsafe_code)]`.
//! - **A plain read kept by `black_box`**, everywhere else (and under Miri). An out-of-order
//!   core overlaps it with the visits in flight, but the read must complete before it retires,
//!   so it hides less.
//!
//! The instruction hides more of the wait than the read, because it retires at once. How far
//! ahead to ask is set by the visit's cost: certificates answer most visits without reading
//! the bounds, so a visit takes only a few nanoseconds, and the lines need several visits'
//! time to arrive; the pass therefore asks `PREFETCH_AHEAD` records ahead, enough to cover a
//! last-level-cache miss, and also asks for the pair-map entry a refusal check will read.

use crate::format::SplitBounds;

/// Asks for `b`'s cache line ahead of its use.
#[inline(always)]
pub(crate) fn bounds(b: &SplitBounds) {
    line(b);
}

/// Asks for the cache line holding `x` ahead of its use.
#[inline(always)]
pub(crate) fn line<T: Copy>(x: &T) {
    #[cfg(all(feature = "prefetch", target_arch = "x86_64", not(miri)))]
    {
        use core::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        #[allow(unsafe_code)]
        // SAFETY: `prefetcht0` only hints the cache: it cannot fault, whatever the address,
        // and reads or writes no architectural state; `x` is a valid reference besides. SSE,
        // the feature the intrinsic is declared with, is in the x86-64 baseline.
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>((x as *const T).cast::<i8>());
        }
    }
    #[cfg(not(all(feature = "prefetch", target_arch = "x86_64", not(miri))))]
    {
        core::hint::black_box(*x);
    }
}
