//! A paged file's root over caller bytes: open it (validated once), its counts, and where
//! each page lies.

use caveclod_core::format::paged::PagedRoot;

use crate::ffi::{self, guarded, Result};
use crate::hierarchy::CAVECLOD_BYTES_ALIGN;
use crate::status::CaveclodStatus;

/// Words (of 8 bytes) of a `CaveclodPagedRoot`.
pub const CAVECLOD_PAGED_ROOT_WORDS: usize = 64;

/// A validated paged-file root over the caller's root bytes (the file's first
/// `header.file_len` bytes): an opaque value the caller places anywhere and
/// `caveclod_paged_root_open` fills. Like `CaveclodHierarchy`, it holds no memory and needs
/// no closing; the root bytes must outlive it and every pool it was added to.
#[repr(C)]
pub struct CaveclodPagedRoot {
    opaque: [u64; CAVECLOD_PAGED_ROOT_WORDS],
}

pub(crate) const PAGED_ROOT_TAG: u64 = u64::from_le_bytes(*b"ccldRoot");

const _: () = assert!(ffi::fits::<CaveclodPagedRoot, PagedRoot<'static>>());

/// The counts of a paged file.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CaveclodPagedCounts {
    /// Pages, the root's included.
    pub pages: u32,
    /// Pages `0..root_pages` lie in the root and are always resident.
    pub root_pages: u32,
    /// The largest streamed page, in bytes: a pool's slots must hold it.
    pub largest_page: u32,
    /// Surfaces (index lists).
    pub surfaces: u32,
    /// The most vertices a streamed page holds: a device vertex pool's `slot_vertices`.
    pub most_page_vertices: u32,
    /// The root pages' vertices: what the file needs of a device vertex pool past its slots.
    pub root_vertices: u32,
    /// The root's bytes.
    pub root_bytes: u64,
    /// The whole file's bytes.
    pub file_bytes: u64,
}

/// Where a page lies and what loading it is worth.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CaveclodPageInfo {
    /// Where its bytes start in the file.
    pub offset: u64,
    /// Its length in bytes.
    pub size: u32,
    /// Pages that must be resident before it.
    pub parent_count: u32,
    /// The largest error bound of its splits (world units).
    pub max_error: f32,
    /// Lower corner of the box around what its splits touch.
    pub bounds_min: [f32; 3],
    /// Upper corner of that box.
    pub bounds_max: [f32; 3],
}

/// The root of an initialised handle.
///
/// # Safety
/// `r` is null or points to a `CaveclodPagedRoot` that nothing writes during the call.
pub(crate) unsafe fn paged_root<'a>(r: *const CaveclodPagedRoot) -> Result<&'a PagedRoot<'static>> {
    // SAFETY: the caller's contract; the tag says whether a root was written there.
    unsafe { ffi::handle(r, PAGED_ROOT_TAG) }
}

/// Validates the root of a paged file in `bytes[0..len]` (exactly the root: the header's
/// `file_len` bytes, read from the file's start) and makes `out` view it in place.
///
/// Returns `CAVECLOD_STATUS_NULL_POINTER`, `CAVECLOD_STATUS_MISALIGNED` (`bytes` not aligned
/// to `CAVECLOD_BYTES_ALIGN`), `CAVECLOD_STATUS_TRUNCATED`, `CAVECLOD_STATUS_NOT_A_CLOD_FILE`,
/// `CAVECLOD_STATUS_CORRUPT` or `CAVECLOD_STATUS_INVALID_FILE`. On failure `out` is left a
/// handle every other call refuses.
///
/// Thread-safety: any thread; `out` must not be used by another thread during the call.
///
/// # Safety
/// `bytes` is null or valid for reads of `len` bytes that are neither written nor freed
/// while the root, or a pool it was added to, is in use; `out` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_paged_root_open(
    bytes: *const u8,
    len: usize,
    out: *mut CaveclodPagedRoot,
) -> CaveclodStatus {
    guarded(|| {
        let out = ffi::checked(out.cast_const())?.cast_mut();
        // SAFETY: `out` is non-null, aligned and writable (the caller's contract).
        unsafe { ffi::clear_tag::<_, PagedRoot<'static>>(out) };
        if bytes.is_null() {
            return Err(CaveclodStatus::NullPointer);
        }
        if bytes.align_offset(CAVECLOD_BYTES_ALIGN) != 0 {
            return Err(CaveclodStatus::Misaligned);
        }
        // SAFETY: non-null and valid for `len` unchanging bytes while the handle is used
        // (the caller's contract), which is what `'static` stands for here.
        let bytes: &'static [u8] = unsafe { core::slice::from_raw_parts(bytes, len) };
        let root = PagedRoot::from_bytes(bytes).map_err(CaveclodStatus::from_format)?;
        // SAFETY: `out` is writable and the blob holds a `Cell<PagedRoot>` (asserted).
        unsafe { ffi::fill(out, PAGED_ROOT_TAG, root) };
        Ok(())
    })
}

/// Writes the counts of the paged file whose root is `r` to `out`.
///
/// Thread-safety: any thread, concurrently with any call that reads `r`.
///
/// # Safety
/// `r` is null or an opened root; `out` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_paged_root_counts(
    r: *const CaveclodPagedRoot,
    out: *mut CaveclodPagedCounts,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let r = unsafe { paged_root(r) }?;
        let p = r.paged();
        let counts = CaveclodPagedCounts {
            pages: p.page_count,
            root_pages: p.root_pages,
            largest_page: p.largest_page,
            surfaces: r.meta().surface_count,
            most_page_vertices: r.table().most_vertices_from(p.root_pages),
            root_vertices: u32::try_from(r.table().vertices_before(p.root_pages))
                .unwrap_or(u32::MAX),
            root_bytes: r.bytes().len() as u64,
            file_bytes: p.file_len,
        };
        // SAFETY: the caller's contract.
        unsafe { ffi::output(out, counts) }
    })
}

/// Writes where page `page` lies, and what loading it is worth, to `out`;
/// `CAVECLOD_STATUS_INVALID_ARGUMENT` for a page the file does not have.
///
/// Thread-safety: any thread, concurrently with any call that reads `r`.
///
/// # Safety
/// `r` is null or an opened root; `out` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_paged_root_page(
    r: *const CaveclodPagedRoot,
    page: u32,
    out: *mut CaveclodPageInfo,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let r = unsafe { paged_root(r) }?;
        let e = r
            .table()
            .entry(page)
            .ok_or(CaveclodStatus::InvalidArgument)?;
        let info = CaveclodPageInfo {
            offset: e.offset,
            size: e.size,
            parent_count: e.parent_count,
            max_error: e.max_error,
            bounds_min: e.bounds_min,
            bounds_max: e.bounds_max,
        };
        // SAFETY: the caller's contract.
        unsafe { ffi::output(out, info) }
    })
}
