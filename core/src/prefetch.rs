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
//! Measured on the St. Helens demo (2-core VM, 4 runs alternating, refinement time of four
//! cameras together over one alone): 4.44-5.01x with the read, 4.20-4.40x with the
//! instruction. Since certificates answer most visits without a read, a visit takes a few
//! nanoseconds and 8 records ahead no longer gave the lines time to arrive: on the same
//! flights (a probe timing each camera alone and four together, 16 runs of each variant
//! alternating), four cameras took 1.227x the time of one camera alone per camera with
//! 8 records, 1.171x when the pass also asks for the pair-map entry a refusal check will
//! read, 1.121-1.178x looking 16 records ahead (32: 1.127x); without any prefetch, 1.38x.

use crate::records::SplitBounds;

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
