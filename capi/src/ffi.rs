//! The boundary: every entry point runs inside [`guarded`], and reads its pointers through
//! the checks here (null, alignment, a handle's tag) before it makes a reference.

use core::panic::AssertUnwindSafe;

use crate::status::CaveclodStatus;

/// The result of a checked step.
pub(crate) type Result<T> = core::result::Result<T, CaveclodStatus>;

/// Runs `body`, turning its error into a status and a panic into
/// [`CaveclodStatus::Internal`]: nothing unwinds across the C boundary.
pub(crate) fn guarded(body: impl FnOnce() -> Result<()>) -> CaveclodStatus {
    match std::panic::catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => CaveclodStatus::Ok,
        Ok(Err(status)) => status,
        Err(_) => CaveclodStatus::Internal,
    }
}

/// `p` if it is non-null and aligned for `T`.
pub(crate) fn checked<T>(p: *const T) -> Result<*const T> {
    if p.is_null() {
        Err(CaveclodStatus::NullPointer)
    } else if !p.is_aligned() {
        Err(CaveclodStatus::Misaligned)
    } else {
        Ok(p)
    }
}

/// A shared reference to a caller's input struct.
///
/// # Safety
/// `p` is null or points to a valid `T` that nothing writes for `'a`.
pub(crate) unsafe fn input<'a, T>(p: *const T) -> Result<&'a T> {
    let p = checked(p)?;
    // SAFETY: non-null and aligned (checked); valid and unaliased by the caller's contract.
    Ok(unsafe { &*p })
}

/// Writes `value` to a caller's output struct (which may be uninitialised).
///
/// # Safety
/// `p` is null or points to memory writable as a `T`.
pub(crate) unsafe fn output<T>(p: *mut T, value: T) -> Result<()> {
    let p = checked(p.cast_const())?.cast_mut();
    // SAFETY: non-null and aligned (checked); writable by the caller's contract; `write`
    // reads nothing, so the old contents may be uninitialised.
    unsafe { p.write(value) };
    Ok(())
}

/// [`output`] where a null pointer means "not wanted".
///
/// # Safety
/// As [`output`].
pub(crate) unsafe fn optional_output<T>(p: *mut T, value: T) -> Result<()> {
    if p.is_null() {
        return Ok(());
    }
    // SAFETY: forwarded contract.
    unsafe { output(p, value) }
}

/// A mutable slice of `len` elements at `p`; a null `p` is allowed only for `len == 0`.
///
/// # Safety
/// `p` is null or valid for reads and writes of `len` elements of `T`, which nothing else
/// reads or writes for `'a`.
pub(crate) unsafe fn slice_mut<'a, T>(p: *mut T, len: usize) -> Result<&'a mut [T]> {
    if len == 0 && p.is_null() {
        return Ok(&mut []);
    }
    let p = checked(p.cast_const())?.cast_mut();
    // SAFETY: non-null, aligned (checked), valid for `len` elements and unaliased by the
    // caller's contract.
    Ok(unsafe { core::slice::from_raw_parts_mut(p, len) })
}

/// A shared slice of `len` elements at `p`; a null `p` is allowed only for `len == 0`.
///
/// # Safety
/// `p` is null or valid for reads of `len` elements of `T`, which nothing writes for `'a`.
pub(crate) unsafe fn slice<'a, T>(p: *const T, len: usize) -> Result<&'a [T]> {
    if len == 0 && p.is_null() {
        return Ok(&[]);
    }
    let p = checked(p)?;
    // SAFETY: non-null, aligned (checked), valid for `len` elements by the caller's contract.
    Ok(unsafe { core::slice::from_raw_parts(p, len) })
}

/// A handle's contents behind its opaque blob: a tag that says the blob was initialised,
/// then the Rust value. The cell sits at the first address in the blob aligned for it (the
/// blob is a `uint64_t` array, aligned to 8; a value that needs 16 sits 8 bytes in where
/// the blob is not 16-aligned).
#[repr(C)]
pub(crate) struct Cell<T> {
    pub tag: u64,
    pub value: T,
}

/// The caller's memory for a handle, checked: non-null (`NullPointer`), aligned to `align`
/// (`Misaligned`), at least `needed` of its `bytes` (`MemoryTooSmall`).
pub(crate) fn caller_memory(
    memory: *mut core::ffi::c_void,
    align: usize,
    bytes: usize,
    needed: usize,
) -> Result<*mut u8> {
    if memory.is_null() {
        return Err(CaveclodStatus::NullPointer);
    }
    if memory.align_offset(align) != 0 {
        return Err(CaveclodStatus::Misaligned);
    }
    if bytes < needed {
        return Err(CaveclodStatus::MemoryTooSmall);
    }
    Ok(memory.cast())
}

/// `true` if a `Cell<T>` fits in a blob `B` wherever an 8-aligned `B` lies.
pub(crate) const fn fits<B, T>() -> bool {
    let cell = core::mem::size_of::<Cell<T>>();
    let slack = core::mem::align_of::<Cell<T>>().saturating_sub(8);
    core::mem::align_of::<B>() >= 8 && cell + slack <= core::mem::size_of::<B>()
}

/// Where the cell of blob `blob` lies.
fn cell_of<B, T>(blob: *mut B) -> *mut Cell<T> {
    let offset = blob
        .cast::<u8>()
        .align_offset(core::mem::align_of::<Cell<T>>());
    blob.cast::<u8>().wrapping_add(offset).cast()
}

/// The value in the initialised handle `blob` of type `B`, which holds a `Cell<T>` tagged
/// `tag`.
///
/// # Safety
/// `blob` is null or points to a `B` that nothing writes for `'a`; a `B` whose cell starts
/// with `tag` holds a `Cell<T>` written by this library; `fits::<B, T>()`.
pub(crate) unsafe fn handle<'a, B, T>(blob: *const B, tag: u64) -> Result<&'a T> {
    let cell = cell_of::<B, T>(checked(blob)?.cast_mut());
    // SAFETY: the cell lies inside the blob (`fits`), aligned for `Cell<T>`, so for its
    // leading `u64`, readable by the caller's contract.
    if unsafe { cell.cast::<u64>().read() } != tag {
        return Err(CaveclodStatus::InvalidHandle);
    }
    // SAFETY: the tag says this library wrote a `Cell<T>` there.
    Ok(unsafe { &(*cell).value })
}

/// [`handle`] for a handle the call changes.
///
/// # Safety
/// `blob` is null or points to a `B` that nothing else reads or writes for `'a`; otherwise
/// as [`handle`].
pub(crate) unsafe fn handle_mut<'a, B, T>(blob: *mut B, tag: u64) -> Result<&'a mut T> {
    let cell = cell_of::<B, T>(checked(blob.cast_const())?.cast_mut());
    // SAFETY: as in `handle`.
    if unsafe { cell.cast::<u64>().read() } != tag {
        return Err(CaveclodStatus::InvalidHandle);
    }
    // SAFETY: as in `handle`, and the caller's contract makes the access exclusive.
    Ok(unsafe { &mut (*cell).value })
}

/// Marks the blob at `blob` as holding no `T` (its cell's tag cleared), so a failed
/// `_open` or `_init` leaves a handle every other call refuses.
///
/// # Safety
/// `blob` is non-null, aligned and writable for a `B`; `fits::<B, T>()`.
pub(crate) unsafe fn clear_tag<B, T>(blob: *mut B) {
    // SAFETY: the cell's leading `u64` lies inside the writable blob (`fits`), aligned.
    unsafe { cell_of::<B, T>(blob).cast::<u64>().write(0) };
}

/// Writes `value` into the blob at `blob` under `tag`, making it an initialised handle.
///
/// # Safety
/// `blob` is non-null, aligned and writable for a `B`; `fits::<B, T>()`.
pub(crate) unsafe fn fill<B, T>(blob: *mut B, tag: u64, value: T) {
    // SAFETY: the cell lies inside the writable blob (`fits`), aligned for it; `write`
    // drops nothing that was there.
    unsafe { cell_of::<B, T>(blob).write(Cell { tag, value }) };
}
