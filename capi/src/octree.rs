//! The multiresolution octree of an out-of-core bake and one camera's cut of it, in the
//! cameras' pattern: open over the hierarchy's bytes, a cut in caller memory, select,
//! emit packed.
//!
//! Left out: per-surface emission of a cut (the packed list's offsets give each surface's
//! range) and the entered/left node lists (streaming is the caller's own business; the
//! counts are in the stats).

use caveclod_core::{Octree, OctreeCut};

use crate::camera::CAVECLOD_MEMORY_ALIGN;
use crate::ffi::{self, guarded, Result};
use crate::hierarchy::{hierarchy, CaveclodHierarchy};
use crate::status::CaveclodStatus;
use crate::types::CaveclodView;

/// Words (of 8 bytes) of a `CaveclodOctree`.
pub const CAVECLOD_OCTREE_WORDS: usize = 32;
/// Words (of 8 bytes) of a `CaveclodOctreeCut`.
pub const CAVECLOD_OCTREE_CUT_WORDS: usize = 16;

/// The validated octree of a file baked out of core: an opaque value like
/// `CaveclodHierarchy` (nothing to free, may be copied, shared by any number of threads).
#[repr(C)]
pub struct CaveclodOctree {
    opaque: [u64; CAVECLOD_OCTREE_WORDS],
}

/// One camera's cut of an octree, in caller memory: an opaque value like `CaveclodCamera`
/// (never copied; one thread at a time).
#[repr(C)]
pub struct CaveclodOctreeCut {
    opaque: [u64; CAVECLOD_OCTREE_CUT_WORDS],
}

/// The counts of an octree.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CaveclodOctreeCounts {
    /// Surfaces (the hierarchy's).
    pub surfaces: u32,
    /// Vertices of the octree's own vertex buffer (32 bytes each, the hierarchy's layout);
    /// every index a cut emits is below it.
    pub vertices: u32,
    /// Bytes of that vertex buffer.
    pub vertex_buffer_bytes: u64,
    /// Nodes (blocks of all levels).
    pub nodes: u32,
    /// Levels; the root's is `levels - 1`.
    pub levels: u32,
}

/// What one selection did (the core's `SelectStats`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CaveclodSelectStats {
    /// Nodes in the cut.
    pub selected: u32,
    /// Triangles of the cut, all surfaces.
    pub triangles: u32,
    /// Nodes in the cut that were not in the previous one.
    pub entered: u32,
    /// Nodes of the previous cut that are not in this one.
    pub left: u32,
    /// Nodes skipped with their subtrees, outside the frustum.
    pub culled: u32,
    /// Nodes looked at.
    pub visited: u32,
}

const OCTREE_TAG: u64 = u64::from_le_bytes(*b"ccldOctr");
const CUT_TAG: u64 = u64::from_le_bytes(*b"ccldCutt");

const _: () = assert!(
    ffi::fits::<CaveclodOctree, Octree<'static>>()
        && core::mem::align_of::<ffi::Cell<Octree<'static>>>() <= 8
        && ffi::fits::<CaveclodOctreeCut, OctreeCut<'static>>()
);

/// The octree of an initialised handle.
///
/// # Safety
/// `o` is null or points to a `CaveclodOctree` nothing writes during the call.
unsafe fn octree<'a>(o: *const CaveclodOctree) -> Result<&'a Octree<'static>> {
    // SAFETY: the caller's contract.
    unsafe { ffi::handle(o, OCTREE_TAG) }
}

/// The cut of an initialised handle, checked to belong to `o`.
///
/// # Safety
/// `cut` is null or points to a `CaveclodOctreeCut` nothing else uses during the call.
unsafe fn cut_for<'a>(
    cut: *mut CaveclodOctreeCut,
    o: &Octree<'_>,
) -> Result<&'a mut OctreeCut<'static>> {
    // SAFETY: the caller's contract.
    let cut: &mut OctreeCut<'static> = unsafe { ffi::handle_mut(cut, CUT_TAG) }?;
    if cut.is_for(o) {
        Ok(cut)
    } else {
        Err(CaveclodStatus::WrongHierarchy)
    }
}

/// Makes `out` the octree stored in `h`'s file. `CAVECLOD_STATUS_NO_OCTREE` when the file
/// has none, `CAVECLOD_STATUS_INVALID_FILE` when its octree sections are invalid.
///
/// Thread-safety: any thread, concurrently with any call that reads `h`.
///
/// # Safety
/// `h` is null or an opened hierarchy (its bytes outlive the octree); `out` is null or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_octree_open(
    h: *const CaveclodHierarchy,
    out: *mut CaveclodOctree,
) -> CaveclodStatus {
    guarded(|| {
        let out = ffi::checked(out.cast_const())?.cast_mut();
        // SAFETY: `out` is non-null, aligned and writable (the caller's contract).
        unsafe { ffi::clear_tag::<_, Octree<'static>>(out) };
        // SAFETY: the caller's contract.
        let h = unsafe { hierarchy(h) }?;
        let o = Octree::from_hierarchy(h)?.ok_or(CaveclodStatus::NoOctree)?;
        // SAFETY: `out` is writable and the blob holds a `Cell<Octree>` (asserted).
        unsafe { ffi::fill(out, OCTREE_TAG, o) };
        Ok(())
    })
}

/// Writes the counts of `o` to `out`.
///
/// Thread-safety: any thread, concurrently with any call that reads `o`.
///
/// # Safety
/// `o` is null or an opened octree; `out` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_octree_counts(
    o: *const CaveclodOctree,
    out: *mut CaveclodOctreeCounts,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let o = unsafe { octree(o) }?;
        let counts = CaveclodOctreeCounts {
            surfaces: o.surface_count() as u32,
            vertices: o.vertices().len() as u32,
            vertex_buffer_bytes: core::mem::size_of_val(o.vertices()) as u64,
            nodes: o.node_count() as u32,
            levels: o.level_count(),
        };
        // SAFETY: the caller's contract.
        unsafe { ffi::output(out, counts) }
    })
}

/// Points `*vertices` at the octree's vertex buffer inside the file's bytes and writes its
/// byte length to `*bytes` (upload it once; cuts index into it).
///
/// Thread-safety: any thread, concurrently with any call that reads `o`.
///
/// # Safety
/// `o` is null or an opened octree; `vertices` and `bytes` are null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_octree_vertices(
    o: *const CaveclodOctree,
    vertices: *mut *const core::ffi::c_void,
    bytes: *mut usize,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let v = unsafe { octree(o) }?.vertices();
        // SAFETY: the caller's contract.
        unsafe { ffi::output(vertices, v.as_ptr().cast()) }?;
        // SAFETY: the caller's contract.
        unsafe { ffi::output(bytes, core::mem::size_of_val(v)) }
    })
}

/// Writes to `*bytes` the memory a cut of `o` needs (aligned to `CAVECLOD_MEMORY_ALIGN`).
///
/// Thread-safety: any thread, concurrently with any call that reads `o`.
///
/// # Safety
/// `o` is null or an opened octree; `bytes` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_octree_cut_memory_size(
    o: *const CaveclodOctree,
    bytes: *mut usize,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let o = unsafe { octree(o) }?;
        let n = OctreeCut::words_needed(o)
            .checked_mul(4)
            .ok_or(CaveclodStatus::InvalidArgument)?;
        // SAFETY: the caller's contract.
        unsafe { ffi::output(bytes, n) }
    })
}

/// Makes `out` an empty cut of `o` in `memory[0..bytes]` (at least
/// `caveclod_octree_cut_memory_size` bytes, aligned to `CAVECLOD_MEMORY_ALIGN`; may be
/// uninitialised). Returns `CAVECLOD_STATUS_NULL_POINTER`, `CAVECLOD_STATUS_MISALIGNED` or
/// `CAVECLOD_STATUS_MEMORY_TOO_SMALL` as `caveclod_camera_init` does.
///
/// Thread-safety: any thread, concurrently with any call that reads `o`.
///
/// # Safety
/// `memory` is null or valid for reads and writes of `bytes` bytes that nothing else uses
/// while the cut is in use; `o`'s file bytes outlive the cut; `out` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_octree_cut_init(
    o: *const CaveclodOctree,
    memory: *mut core::ffi::c_void,
    bytes: usize,
    out: *mut CaveclodOctreeCut,
) -> CaveclodStatus {
    guarded(|| {
        let out = ffi::checked(out.cast_const())?.cast_mut();
        // SAFETY: `out` is non-null, aligned and writable (the caller's contract).
        unsafe { ffi::clear_tag::<_, OctreeCut<'static>>(out) };
        // SAFETY: the caller's contract.
        let o = unsafe { octree(o) }?;
        let words = OctreeCut::words_needed(o);
        let needed = words.saturating_mul(4);
        let base = ffi::caller_memory(memory, CAVECLOD_MEMORY_ALIGN, bytes, needed)?.cast::<u32>();
        // SAFETY: valid for `bytes >= 4 * words` bytes; zeroed so every word is initialised.
        unsafe { base.write_bytes(0, words) };
        // SAFETY: aligned, initialised, used only through this cut while it lives (the
        // caller's contract, which is what `'static` stands for here).
        let words: &'static mut [u32] = unsafe { core::slice::from_raw_parts_mut(base, words) };
        let cut = OctreeCut::new(o, words)?;
        // SAFETY: `out` is writable and the blob holds a `Cell<OctreeCut>` (asserted).
        unsafe { ffi::fill(out, CUT_TAG, cut) };
        Ok(())
    })
}

/// Chooses the cut's nodes for `view`: culled by the frustum, refined while a node's error
/// projects to more than `tolerance_px` pixels. Writes what it did to `stats` unless null.
///
/// Returns `CAVECLOD_STATUS_INVALID_ARGUMENT` for a view out of range or a tolerance that is
/// not a finite number above 0 (the cut is then left as it was).
///
/// Thread-safety: the thread that owns `cut`; any number of cuts select over one `o` at
/// once.
///
/// # Safety
/// `cut` is null or a cut nothing else uses during the call; `o` is null or an opened
/// octree; `view` is null or readable; `stats` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_octree_cut_select(
    cut: *mut CaveclodOctreeCut,
    o: *const CaveclodOctree,
    view: *const CaveclodView,
    tolerance_px: f32,
    stats: *mut CaveclodSelectStats,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let o = unsafe { octree(o) }?;
        // SAFETY: the caller's contract.
        let cut = unsafe { cut_for(cut, o) }?;
        // SAFETY: the caller's contract.
        let view = unsafe { ffi::input(view) }?.to_view()?;
        let s = cut.select(o, &view, tolerance_px)?;
        let s = CaveclodSelectStats {
            selected: s.selected,
            triangles: s.triangles,
            entered: s.entered,
            left: s.left,
            culled: s.culled,
            visited: s.visited,
        };
        // SAFETY: the caller's contract.
        unsafe { ffi::optional_output(stats, s) }
    })
}

/// Writes to `*count` the indices of all surfaces of the current cut together.
///
/// Thread-safety: the thread that owns `cut`.
///
/// # Safety
/// `cut` is null or a cut nothing else uses during the call; `o` is null or an opened
/// octree; `count` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_octree_cut_total_index_count(
    cut: *mut CaveclodOctreeCut,
    o: *const CaveclodOctree,
    count: *mut usize,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let o = unsafe { octree(o) }?;
        // SAFETY: the caller's contract.
        let cut = unsafe { cut_for(cut, o) }?;
        // SAFETY: the caller's contract.
        unsafe { ffi::output(count, cut.total_index_count()) }
    })
}

/// Writes the cut's triangle lists back to back into `out` (room for `capacity` indices,
/// pointing into the octree's vertex buffer) and the ranges to `offsets` (`offset_count` at
/// least surfaces + 1), as `caveclod_camera_emit_packed` does; the total goes to `*total`
/// unless null. `CAVECLOD_STATUS_OUTPUT_TOO_SMALL` when either is too small.
///
/// Thread-safety: the thread that owns `cut`, concurrently with any call that reads `o`.
///
/// # Safety
/// `cut` is null or a cut nothing else uses during the call; `o` is null or an opened
/// octree; `out` is null or writable for `capacity` indices, `offsets` null or writable for
/// `offset_count` entries, the two not overlapping.
#[no_mangle]
pub unsafe extern "C" fn caveclod_octree_cut_emit_packed(
    cut: *mut CaveclodOctreeCut,
    o: *const CaveclodOctree,
    out: *mut u32,
    capacity: usize,
    offsets: *mut u32,
    offset_count: usize,
    total: *mut usize,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let o = unsafe { octree(o) }?;
        // SAFETY: the caller's contract.
        let cut = unsafe { cut_for(cut, o) }?;
        if out.is_null() || offsets.is_null() {
            return Err(CaveclodStatus::NullPointer);
        }
        // SAFETY: non-null, valid and disjoint (the caller's contract).
        let (out, offsets) = unsafe {
            (
                ffi::slice_mut(out, capacity)?,
                ffi::slice_mut(offsets, offset_count)?,
            )
        };
        let n = cut.emit_indices_packed(o, out, offsets)?;
        // SAFETY: the caller's contract.
        unsafe { ffi::optional_output(total, n) }
    })
}
