//! Index emission into caller buffers: per-surface counts, per-surface lists, one packed
//! list with offsets, and the morphing vertices a morphed emission points at.

use caveclod_core::{HierarchyRecords, MorphVertex};

use crate::camera::{camera, Camera, CaveclodCamera};
use crate::ffi::{self, guarded, Result};
use crate::hierarchy::{hierarchy, CaveclodHierarchy};
use crate::status::CaveclodStatus;

/// One morphing vertex as the GPU reads it: blend from `from` towards persistent vertex
/// `to` at `t` and write the result where morphed emission points, `vertex_count + slot`.
/// An idle slot has `from == to == UINT32_MAX`: nothing points at it.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CaveclodMorphVertex {
    /// Where the blend starts: the persistent vertex `coarse` (below `vertex_count`), or,
    /// while `coarse` itself morphs, `vertex_count + s`: the blend of slot `s` (a chain of at
    /// most 8 slots; the vertex split again while it morphed).
    pub from: u32,
    /// The fine vertex (the floating child's own).
    pub to: u32,
    /// 0 gives `from`, 1 gives `to`.
    pub t: f32,
    /// The coarse persistent vertex (the parent's).
    pub coarse: u32,
}

const _: () = assert!(
    core::mem::size_of::<CaveclodMorphVertex>() == core::mem::size_of::<MorphVertex>()
        && core::mem::align_of::<CaveclodMorphVertex>() == core::mem::align_of::<MorphVertex>()
);

/// Writes to `*count` the indices surface `surface`'s list needs (3 × its active polygons).
/// `CAVECLOD_STATUS_INVALID_ARGUMENT` for a surface the hierarchy does not have.
///
/// Thread-safety: the thread that owns `cam`.
///
/// # Safety
/// `cam` is null or a camera nothing else uses during the call; `count` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_index_count(
    cam: *mut CaveclodCamera,
    surface: u32,
    count: *mut usize,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let cam = unsafe { camera(cam) }?;
        if surface as usize >= cam.surfaces {
            return Err(CaveclodStatus::InvalidArgument);
        }
        let n = cam.state.index_count(surface as usize);
        // SAFETY: the caller's contract.
        unsafe { ffi::output(count, n) }
    })
}

/// Writes each surface's triangle list to the start of `lists[surface]` (room for
/// `capacities[surface]` indices) and its index count to `written[surface]`, for the
/// hierarchy's surfaces (`list_count` at least the surface count). With `morphed`, every
/// corner whose vertex morphs points at its morph slot (`vertices + slot`); without
/// morphs in progress it writes what plain emission writes. The total goes to `*total`
/// unless that is null. Allocates nothing.
///
/// Returns `CAVECLOD_STATUS_OUTPUT_TOO_SMALL` when `list_count` is below the surface count
/// or a list is shorter than its surface's index count (nothing is written then),
/// `CAVECLOD_STATUS_NULL_POINTER` for a null array or a null list with a non-zero capacity,
/// `CAVECLOD_STATUS_WRONG_HIERARCHY`, or `CAVECLOD_STATUS_INCONSISTENT` (the output is not
/// usable; reset the camera).
///
/// Thread-safety: the thread that owns `cam`, concurrently with any call that reads `h`.
///
/// # Safety
/// `cam` is null or a camera nothing else uses during the call; `h` is null or an opened
/// hierarchy; `lists`, `capacities` and `written` are null or valid for `list_count`
/// entries; each list is null or writable for its capacity, and no two lists (nor a list
/// and `written`, nor either and the camera's memory) overlap.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_emit(
    cam: *mut CaveclodCamera,
    h: *const CaveclodHierarchy,
    lists: *const *mut u32,
    capacities: *const usize,
    written: *mut u32,
    list_count: usize,
    morphed: bool,
    total: *mut usize,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let h = unsafe { hierarchy(h) }?;
        // SAFETY: the caller's contract.
        let cam = unsafe { camera(cam) }?;
        if !cam.state.is_for(h) {
            return Err(CaveclodStatus::WrongHierarchy);
        }
        if lists.is_null() || capacities.is_null() || written.is_null() {
            return Err(CaveclodStatus::NullPointer);
        }
        let ns = cam.surfaces;
        if list_count < ns {
            return Err(CaveclodStatus::OutputTooSmall);
        }
        // SAFETY: non-null, valid for `list_count >= ns` entries (the caller's contract).
        let (pointers, capacities, written) = unsafe {
            (
                ffi::slice(lists, ns)?,
                ffi::slice(capacities, ns)?,
                ffi::slice_mut(written, ns)?,
            )
        };
        for (s, (&p, &cap)) in pointers.iter().zip(capacities).enumerate() {
            // SAFETY: each list is valid for its capacity and overlaps no other output (the
            // caller's contract).
            let list = unsafe { ffi::slice_mut(p, cap) }?;
            // SAFETY: the table has room for the `ns` surfaces of the camera's hierarchy
            // (carved at init); entry `s < ns` is written before the table is read.
            unsafe { cam.lists.add(s).write(list) };
        }
        // SAFETY: all `ns` entries were written just above; the table lies in the camera's
        // memory after its state words, which nothing else borrows.
        let out = unsafe { core::slice::from_raw_parts_mut(cam.lists, ns) };
        let n = if morphed {
            cam.state.emit_indices_morphed(h, out, written)
        } else {
            cam.state.emit_indices(h, out, written)
        }?;
        // SAFETY: the caller's contract.
        unsafe { ffi::optional_output(total, n) }
    })
}

/// Writes every surface's triangle list back to back into `out` (room for `capacity`
/// indices: the camera's `total_indices`), and the ranges to `offsets` (`offset_count` at
/// least surfaces + 1): surface `s` is `out[offsets[s] .. offsets[s + 1]]`. `morphed` and
/// `total` as in `caveclod_camera_emit`. Allocates nothing.
///
/// Returns `CAVECLOD_STATUS_OUTPUT_TOO_SMALL` when `capacity` or `offset_count` is too small
/// (nothing is written then), `CAVECLOD_STATUS_NULL_POINTER`,
/// `CAVECLOD_STATUS_WRONG_HIERARCHY`, or `CAVECLOD_STATUS_INCONSISTENT`.
///
/// Thread-safety: the thread that owns `cam`, concurrently with any call that reads `h`.
///
/// # Safety
/// `cam` is null or a camera nothing else uses during the call; `h` is null or an opened
/// hierarchy; `out` is null or writable for `capacity` indices, `offsets` null or writable
/// for `offset_count` entries, the two not overlapping.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_emit_packed(
    cam: *mut CaveclodCamera,
    h: *const CaveclodHierarchy,
    out: *mut u32,
    capacity: usize,
    offsets: *mut u32,
    offset_count: usize,
    morphed: bool,
    total: *mut usize,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let h = unsafe { hierarchy(h) }?;
        // SAFETY: the caller's contract.
        let cam = unsafe { camera(cam) }?;
        let out = PackedOut {
            out,
            capacity,
            offsets,
            offset_count,
            total,
        };
        // SAFETY: the caller's contract.
        unsafe { emit_packed(cam, h, &out, morphed) }
    })
}

/// Where packed emission writes (see `caveclod_camera_emit_packed`).
pub(crate) struct PackedOut {
    pub out: *mut u32,
    pub capacity: usize,
    pub offsets: *mut u32,
    pub offset_count: usize,
    pub total: *mut usize,
}

/// Packed emission of `cam` over `h` into `o`.
///
/// # Safety
/// `o.out` is null or writable for `o.capacity` indices, `o.offsets` null or writable for
/// `o.offset_count` entries, the two not overlapping; `o.total` null or writable.
pub(crate) unsafe fn emit_packed(
    cam: &Camera,
    h: &impl HierarchyRecords,
    o: &PackedOut,
    morphed: bool,
) -> Result<()> {
    if o.out.is_null() || o.offsets.is_null() {
        return Err(CaveclodStatus::NullPointer);
    }
    // SAFETY: non-null, valid and disjoint (the caller's contract).
    let (out, offsets) = unsafe {
        (
            ffi::slice_mut(o.out, o.capacity)?,
            ffi::slice_mut(o.offsets, o.offset_count)?,
        )
    };
    let n = if morphed {
        cam.state.emit_indices_packed_morphed(h, out, offsets)
    } else {
        cam.state.emit_indices_packed(h, out, offsets)
    }?;
    // SAFETY: the caller's contract.
    unsafe { ffi::optional_output(o.total, n) }
}

/// Points `*vertices` at the camera's morph slots up to the highest in use and writes their
/// number to `*count` (at most 2 × `max_morphs`; 0 when nothing morphs, and then
/// `*vertices` may be dangling). Idle slots between have `from == to == UINT32_MAX`.
/// Slot `i` is what morphed emission's index `vertex_count + i` names. The records live in
/// the camera's memory and stay valid until the camera's next refine or reset.
///
/// Thread-safety: the thread that owns `cam`.
///
/// # Safety
/// `cam` is null or a camera nothing else uses during the call; `vertices` and `count` are
/// null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_morph_vertices(
    cam: *mut CaveclodCamera,
    vertices: *mut *const CaveclodMorphVertex,
    count: *mut usize,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let slots = unsafe { camera(cam) }?.state.morph_vertices();
        // SAFETY: the caller's contract; `CaveclodMorphVertex` has `MorphVertex`'s layout
        // (both `repr(C)`, the same four 32-bit fields; asserted).
        unsafe { ffi::output(vertices, slots.as_ptr().cast::<CaveclodMorphVertex>()) }?;
        // SAFETY: the caller's contract.
        unsafe { ffi::output(count, slots.len()) }
    })
}
