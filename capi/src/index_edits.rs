//! Index edits through the C ABI: a camera that keeps each polygon's place in a device
//! index buffer, and per frame the places that changed, so an engine patches its buffer
//! instead of rewriting it (the core's `CameraState::index_edits`).

use caveclod_core::{CameraConfig, HierarchyRecords, IndexEdit, IndexEdits, SurfaceDraw};

use crate::camera::{camera, camera_memory_size, init_camera, Camera, CaveclodCamera};
use crate::ffi::{self, guarded, Result};
use crate::hierarchy::{hierarchy, CaveclodHierarchy};
use crate::status::CaveclodStatus;
use crate::types::CaveclodCameraConfig;

/// One place of a camera's index buffer and the triangle it now holds: write `indices` to
/// indices `3 × place .. 3 × place + 3` of the buffer. A hole holds three equal indices,
/// which draw nothing.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CaveclodIndexEdit {
    /// The place (a triangle of the buffer).
    pub place: u32,
    /// Its three vertex indices.
    pub indices: [u32; 3],
}

/// One surface's draw over a camera's index buffer: `index_count` indices from
/// `first_index` (what `vkCmdDrawIndexed` or `glDrawElements` take).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CaveclodSurfaceDraw {
    /// The first index.
    pub first_index: u32,
    /// Indices to draw (three per place in use or hole).
    pub index_count: u32,
}

/// What one `caveclod_camera_index_edits` handed out.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CaveclodIndexEdits {
    /// Edits written.
    pub edits: usize,
    /// Polygons moved into holes.
    pub moves: u32,
    /// Holes still drawn (as nothing).
    pub holes: u32,
    /// Every drawn place was written (a new or reset camera, or more changes than the list
    /// holds).
    pub everything: bool,
}

const _: () = assert!(
    core::mem::size_of::<CaveclodIndexEdit>() == core::mem::size_of::<IndexEdit>()
        && core::mem::align_of::<CaveclodIndexEdit>() == core::mem::align_of::<IndexEdit>()
        && core::mem::size_of::<CaveclodSurfaceDraw>() == core::mem::size_of::<SurfaceDraw>()
        && core::mem::align_of::<CaveclodSurfaceDraw>() == core::mem::align_of::<SurfaceDraw>()
);

impl From<IndexEdits> for CaveclodIndexEdits {
    fn from(e: IndexEdits) -> Self {
        Self {
            edits: e.edits,
            moves: e.moves,
            holes: e.holes,
            everything: e.everything,
        }
    }
}

/// The core's configuration of `config` over `h`, keeping index edits with a list of
/// `edit_list` changed places (at least 1; the index cache must be on).
pub(crate) fn edited_config(
    h: &impl HierarchyRecords,
    config: &CaveclodCameraConfig,
    edit_list: u32,
) -> Result<CameraConfig> {
    if edit_list == 0 || !config.index_cache {
        return Err(CaveclodStatus::InvalidConfig);
    }
    Ok(config.to_config(h)?.with_index_edits(edit_list))
}

/// Writes to `*bytes` the memory a camera with `config` keeping index edits (a list of
/// `edit_list` changed places) over `h` needs: `caveclod_camera_memory_size`'s, plus 4 bytes
/// per polygon slot, 4 bytes and two bits per place (a place per slot and surface) and 4
/// bytes per list entry. `CAVECLOD_STATUS_INVALID_CONFIG` as there, and for an `edit_list`
/// of 0 or a configuration without the index cache.
///
/// Thread-safety: any thread, concurrently with any call that reads `h`.
///
/// # Safety
/// `h` is null or an opened hierarchy; `config` is null or readable; `bytes` is null or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_memory_size_edited(
    h: *const CaveclodHierarchy,
    config: *const CaveclodCameraConfig,
    edit_list: u32,
    bytes: *mut usize,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let h = unsafe { hierarchy(h) }?;
        // SAFETY: the caller's contract.
        let config = edited_config(h, unsafe { ffi::input(config) }?, edit_list)?;
        // SAFETY: the caller's contract.
        unsafe { camera_memory_size(h, &config, bytes) }
    })
}

/// `caveclod_camera_init` for a camera keeping index edits (a list of `edit_list` changed
/// places), in memory of `caveclod_camera_memory_size_edited` bytes. Its first
/// `caveclod_camera_index_edits` writes every place.
///
/// Thread-safety: as `caveclod_camera_init`.
///
/// # Safety
/// As `caveclod_camera_init`.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_init_edited(
    h: *const CaveclodHierarchy,
    config: *const CaveclodCameraConfig,
    edit_list: u32,
    memory: *mut core::ffi::c_void,
    bytes: usize,
    out: *mut CaveclodCamera,
) -> CaveclodStatus {
    guarded(|| {
        let out = ffi::checked(out.cast_const())?.cast_mut();
        // SAFETY: `out` is non-null, aligned and writable (the caller's contract).
        unsafe { ffi::clear_tag::<_, Camera>(out) };
        // SAFETY: the caller's contract.
        let h = unsafe { hierarchy(h) }?;
        // SAFETY: the caller's contract.
        let config = edited_config(h, unsafe { ffi::input(config) }?, edit_list)?;
        // SAFETY: the caller's contract.
        unsafe { init_camera(h, &config, memory, bytes, out) }
    })
}

/// Writes to `*places` the triangles of the camera's index buffer: the buffer holds
/// `3 × places` indices (0 for a camera without index edits).
///
/// Thread-safety: the thread that owns `cam`.
///
/// # Safety
/// `cam` is null or a camera nothing else uses during the call; `places` is null or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_index_places(
    cam: *mut CaveclodCamera,
    places: *mut usize,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let cam = unsafe { camera(cam) }?;
        // SAFETY: the caller's contract.
        unsafe { ffi::output(places, cam.state.index_places()) }
    })
}

/// Writes to `*edits` the most edits the next `caveclod_camera_index_edits` with
/// `max_moves` writes: the room its `out` needs.
///
/// Thread-safety: the thread that owns `cam`.
///
/// # Safety
/// `cam` is null or a camera nothing else uses during the call; `edits` is null or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_index_edits_needed(
    cam: *mut CaveclodCamera,
    max_moves: u32,
    edits: *mut usize,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let cam = unsafe { camera(cam) }?;
        // SAFETY: the caller's contract.
        unsafe { ffi::output(edits, cam.state.index_edits_needed(max_moves)) }
    })
}

/// Moves at most `max_moves` polygons into holes, then writes to `out` (room for `capacity`
/// edits) every place of the camera's index buffer that changed since the last call, with
/// the triangle it now holds (morphed emission's indices when the camera has morph memory),
/// and to `draws` (`draw_count` at least the surfaces) each surface's range; `*result`
/// says what was written. Copy the edits into the buffer before the frame's draws; the
/// draws then show exactly the triangles of `caveclod_camera_emit_packed` (morphed), in
/// another order. Allocates nothing.
///
/// Returns `CAVECLOD_STATUS_OUTPUT_TOO_SMALL` when `capacity` (see
/// `caveclod_camera_index_edits_needed`) or `draw_count` is too small, nothing changed then;
/// `CAVECLOD_STATUS_INVALID_ARGUMENT` for a camera made without index edits;
/// `CAVECLOD_STATUS_NULL_POINTER`; `CAVECLOD_STATUS_WRONG_HIERARCHY`.
///
/// Thread-safety: the thread that owns `cam`, concurrently with any call that reads `h`.
///
/// # Safety
/// `cam` is null or a camera nothing else uses during the call; `h` is null or an opened
/// hierarchy; `out` is null or writable for `capacity` edits, `draws` null or writable for
/// `draw_count` entries, the two not overlapping; `result` null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_index_edits(
    cam: *mut CaveclodCamera,
    h: *const CaveclodHierarchy,
    max_moves: u32,
    out: *mut CaveclodIndexEdit,
    capacity: usize,
    draws: *mut CaveclodSurfaceDraw,
    draw_count: usize,
    result: *mut CaveclodIndexEdits,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let h = unsafe { hierarchy(h) }?;
        // SAFETY: the caller's contract.
        let cam = unsafe { camera(cam) }?;
        // SAFETY: the caller's contract.
        unsafe {
            write_edits(
                cam,
                h,
                max_moves,
                (out, capacity),
                (draws, draw_count),
                result,
            )
        }
    })
}

/// `cam`'s index edits over `h` into `out` and `draws` (pointer and length each), and what
/// they were into `result`.
///
/// # Safety
/// `out` and `draws` are null or valid and disjoint for their lengths; `result` is null or
/// writable.
pub(crate) unsafe fn write_edits(
    cam: &mut Camera,
    h: &impl HierarchyRecords,
    max_moves: u32,
    (out, capacity): (*mut CaveclodIndexEdit, usize),
    (draws, draw_count): (*mut CaveclodSurfaceDraw, usize),
    result: *mut CaveclodIndexEdits,
) -> Result<()> {
    if out.is_null() || draws.is_null() {
        return Err(CaveclodStatus::NullPointer);
    }
    // SAFETY: non-null, valid and disjoint (the caller's contract); the records have the
    // core's layout (asserted).
    let (out, draws) = unsafe {
        (
            ffi::slice_mut(out.cast::<IndexEdit>(), capacity)?,
            ffi::slice_mut(draws.cast::<SurfaceDraw>(), draw_count)?,
        )
    };
    let e = cam.state.index_edits(h, max_moves, out, draws)?;
    // SAFETY: the caller's contract.
    unsafe { ffi::output(result, e.into()) }
}
