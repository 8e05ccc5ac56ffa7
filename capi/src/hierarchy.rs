//! A hierarchy over caller bytes: open (validate once), counts, the vertex buffer.

use caveclod_core::Hierarchy;

use crate::ffi::{self, guarded, Result};
use crate::status::CaveclodStatus;
use crate::types::{CaveclodBounds, CaveclodHierarchyCounts};

/// Words (of 8 bytes) of a `CaveclodHierarchy`.
pub const CAVECLOD_HIERARCHY_WORDS: usize = 64;

/// Alignment, in bytes, that the bytes of a `.clod` file must have. 64 is better: sections
/// start on multiples of 64, so no record a refinement pass reads straddles cache lines.
pub const CAVECLOD_BYTES_ALIGN: usize = 4;

/// A validated hierarchy over the caller's file bytes: an opaque value the caller allocates
/// (on the stack, in a struct, in an arena) and `caveclod_hierarchy_open` fills. It holds
/// no memory of its own and needs no closing: it is dropped by forgetting it, and the file
/// bytes may be freed once no camera and no call uses it. It may be copied (the copy views
/// the same bytes).
#[repr(C)]
pub struct CaveclodHierarchy {
    opaque: [u64; CAVECLOD_HIERARCHY_WORDS],
}

pub(crate) const HIERARCHY_TAG: u64 = u64::from_le_bytes(*b"ccldHier");

// A hierarchy's cell needs no more than the blob's alignment, so it sits at the blob's
// start wherever the blob is: a copy of the blob is a copy of the handle.
const _: () = assert!(
    ffi::fits::<CaveclodHierarchy, Hierarchy<'static>>()
        && core::mem::align_of::<ffi::Cell<Hierarchy<'static>>>() <= 8
);

/// The hierarchy of an initialised handle.
///
/// # Safety
/// `h` is null or points to a `CaveclodHierarchy` that nothing writes during the call.
pub(crate) unsafe fn hierarchy<'a>(h: *const CaveclodHierarchy) -> Result<&'a Hierarchy<'static>> {
    // SAFETY: the caller's contract; the tag says whether a `Hierarchy` was written there.
    unsafe { ffi::handle(h, HIERARCHY_TAG) }
}

/// Validates the `.clod` file in `bytes[0..len]` once (every index, count, invariant and
/// the checksum) and makes `out` a hierarchy that views it in place. Nothing is copied or
/// allocated.
///
/// Returns `CAVECLOD_STATUS_NULL_POINTER` for a null `bytes` or `out`,
/// `CAVECLOD_STATUS_MISALIGNED` when `bytes` is not aligned to `CAVECLOD_BYTES_ALIGN`,
/// `CAVECLOD_STATUS_TRUNCATED`, `CAVECLOD_STATUS_TRAILING_BYTES` (more bytes than the file
/// records), `CAVECLOD_STATUS_NOT_A_CLOD_FILE`, `CAVECLOD_STATUS_CORRUPT` or
/// `CAVECLOD_STATUS_INVALID_FILE` for bytes that are not a valid file, and
/// `CAVECLOD_STATUS_PAGED` for a paged file's bytes. On failure `out` is
/// left a handle every other call refuses.
///
/// Thread-safety: any thread; `out` must not be used by another thread during the call.
/// Once open, one hierarchy may be shared by any number of threads and cameras at once:
/// nothing changes it.
///
/// # Safety
/// `bytes` is null or valid for reads of `len` bytes, and those bytes are neither written
/// nor freed while the hierarchy, or any camera made with it, is in use. `out` is null or
/// points to writable memory for a `CaveclodHierarchy`.
#[no_mangle]
pub unsafe extern "C" fn caveclod_hierarchy_open(
    bytes: *const u8,
    len: usize,
    out: *mut CaveclodHierarchy,
) -> CaveclodStatus {
    guarded(|| {
        let out = ffi::checked(out.cast_const())?.cast_mut();
        // SAFETY: `out` is non-null, aligned and writable (the caller's contract).
        unsafe { ffi::clear_tag::<_, Hierarchy<'static>>(out) };
        if bytes.is_null() {
            return Err(CaveclodStatus::NullPointer);
        }
        if bytes.align_offset(CAVECLOD_BYTES_ALIGN) != 0 {
            return Err(CaveclodStatus::Misaligned);
        }
        // SAFETY: non-null and valid for `len` bytes that stay unchanged while the handle
        // is used (the caller's contract), which is what `'static` stands for here.
        let bytes: &'static [u8] = unsafe { core::slice::from_raw_parts(bytes, len) };
        let h = Hierarchy::from_bytes(bytes).map_err(CaveclodStatus::from_format)?;
        // SAFETY: `out` is writable and the blob holds a `Cell<Hierarchy>` (asserted).
        unsafe { ffi::fill(out, HIERARCHY_TAG, h) };
        Ok(())
    })
}

/// Writes the counts of `h` to `out`: surfaces, vertices, the vertex buffer's bytes and
/// layout, nodes, splits and polygons.
///
/// Thread-safety: any thread, concurrently with any call that reads `h`.
///
/// # Safety
/// `h` is null or an opened hierarchy; `out` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_hierarchy_counts(
    h: *const CaveclodHierarchy,
    out: *mut CaveclodHierarchyCounts,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let h = unsafe { hierarchy(h) }?;
        let counts = counts_of(h);
        // SAFETY: the caller's contract.
        unsafe { ffi::output(out, counts) }
    })
}

/// The counts of `h`.
pub(crate) fn counts_of(h: &Hierarchy<'_>) -> CaveclodHierarchyCounts {
    let stride = core::mem::size_of::<caveclod_core::format::Vertex>();
    CaveclodHierarchyCounts {
        surfaces: h.surface_count() as u32,
        vertices: h.vertices().len() as u32,
        vertex_buffer_bytes: core::mem::size_of_val(h.vertices()) as u64,
        vertex_stride: stride as u32,
        position_offset: 0,
        normal_offset: 12,
        uv_offset: 24,
        nodes: h.node_count() as u32,
        splits: h.splits().len() as u32,
        base_polygons: h.base_polygon_count() as u32,
        polygons: h.polygon_count() as u32,
    }
}

const _: () = assert!(core::mem::size_of::<caveclod_core::format::Vertex>() == 32);

/// Writes the bounding box of `h`'s positions (the model's extent, as baked) to `out`:
/// where to place a first camera without reading the vertex buffer.
///
/// Thread-safety: any thread, concurrently with any call that reads `h`.
///
/// # Safety
/// `h` is null or an opened hierarchy; `out` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_hierarchy_bounds(
    h: *const CaveclodHierarchy,
    out: *mut CaveclodBounds,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let h = unsafe { hierarchy(h) }?;
        let m = h.meta();
        let bounds = CaveclodBounds {
            min: m.bounds_min,
            max: m.bounds_max,
        };
        // SAFETY: the caller's contract.
        unsafe { ffi::output(out, bounds) }
    })
}

/// Points `*vertices` at the persistent vertex buffer inside the file's bytes
/// (`counts.vertex_buffer_bytes` bytes, `counts.vertex_stride` per vertex; upload it once)
/// and writes its byte length to `*bytes`.
///
/// Thread-safety: any thread, concurrently with any call that reads `h`.
///
/// # Safety
/// `h` is null or an opened hierarchy; `vertices` and `bytes` are null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_hierarchy_vertices(
    h: *const CaveclodHierarchy,
    vertices: *mut *const core::ffi::c_void,
    bytes: *mut usize,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let h = unsafe { hierarchy(h) }?;
        let v = h.vertices();
        // SAFETY: the caller's contract.
        unsafe { ffi::output(vertices, v.as_ptr().cast()) }?;
        // SAFETY: the caller's contract.
        unsafe { ffi::output(bytes, core::mem::size_of_val(v)) }
    })
}
