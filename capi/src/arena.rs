//! A bump arena over one caller buffer: what a console-style runtime reserves at start and
//! carves every buffer from (file bytes, cameras, index lists), with a full arena reported
//! as `CAVECLOD_STATUS_ARENA_FULL`, never a crash.

use crate::ffi::{self, guarded};
use crate::status::CaveclodStatus;

/// A bump arena: `used` of `size` bytes at `base` are taken. Plain data: the caller may
/// read it (and rewind `used` to a value it read before to free what came after).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CaveclodArena {
    /// First byte of the buffer.
    pub base: *mut u8,
    /// Bytes of the buffer.
    pub size: usize,
    /// Bytes taken, from the start.
    pub used: usize,
}

/// Makes `arena` an empty arena over `buffer[0..size]`.
///
/// Thread-safety: an arena belongs to one thread at a time.
///
/// # Safety
/// `arena` is null or writable; `buffer` is null or valid for reads and writes of `size`
/// bytes while the arena and what it handed out are in use.
#[no_mangle]
pub unsafe extern "C" fn caveclod_arena_init(
    arena: *mut CaveclodArena,
    buffer: *mut core::ffi::c_void,
    size: usize,
) -> CaveclodStatus {
    guarded(|| {
        if buffer.is_null() {
            return Err(CaveclodStatus::NullPointer);
        }
        let value = CaveclodArena {
            base: buffer.cast(),
            size,
            used: 0,
        };
        // SAFETY: the caller's contract.
        unsafe { ffi::output(arena, value) }
    })
}

/// Takes `size` bytes aligned to `align` (a power of two) from `arena` and points `*out` at
/// them (contents unspecified). `CAVECLOD_STATUS_ARENA_FULL` when they do not fit (the
/// arena is unchanged and `*out` is null), `CAVECLOD_STATUS_INVALID_ARGUMENT` for an
/// `align` that is not a power of two.
///
/// Thread-safety: the thread that owns `arena`.
///
/// # Safety
/// `arena` is null or an arena made by `caveclod_arena_init` (or a copy of one) that
/// nothing else uses during the call; `out` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_arena_alloc(
    arena: *mut CaveclodArena,
    size: usize,
    align: usize,
    out: *mut *mut core::ffi::c_void,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        unsafe { ffi::output(out, core::ptr::null_mut()) }?;
        let a = ffi::checked(arena.cast_const())?.cast_mut();
        // SAFETY: non-null, aligned, and the caller's contract makes it exclusive.
        let a = unsafe { &mut *a };
        if !align.is_power_of_two() {
            return Err(CaveclodStatus::InvalidArgument);
        }
        let start_addr = (a.base as usize)
            .checked_add(a.used)
            .and_then(|p| p.checked_next_multiple_of(align))
            .ok_or(CaveclodStatus::ArenaFull)?;
        let start = start_addr - a.base as usize;
        let end = start.checked_add(size).ok_or(CaveclodStatus::ArenaFull)?;
        if end > a.size {
            return Err(CaveclodStatus::ArenaFull);
        }
        a.used = end;
        // SAFETY: `start <= end <= size`, inside the arena's buffer (the caller's contract).
        let p = unsafe { a.base.add(start) };
        // SAFETY: the caller's contract.
        unsafe { ffi::output(out, p.cast()) }
    })
}
