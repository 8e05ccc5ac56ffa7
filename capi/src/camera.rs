//! Cameras in caller memory: sizing for a configuration, init, reset, refinement, counts.
//!
//! A camera's memory holds the core's `CameraState` words and, after them, a table of one
//! slice per surface that per-surface emission builds its output lists in (so emission
//! allocates nothing for any number of surfaces).

use caveclod_core::{CameraConfig, CameraState, HierarchyRecords, RefineParams};

use crate::ffi::{self, guarded, Result};
use crate::hierarchy::{hierarchy, CaveclodHierarchy};
use crate::status::CaveclodStatus;
use crate::types::{
    CaveclodCameraConfig, CaveclodCameraCounts, CaveclodRefineParams, CaveclodRefineStats,
    CaveclodView,
};

/// Words (of 8 bytes) of a `CaveclodCamera`.
pub const CAVECLOD_CAMERA_WORDS: usize = 128;

/// Alignment, in bytes, of the memory given to `caveclod_camera_init` and
/// `caveclod_octree_cut_init`.
pub const CAVECLOD_MEMORY_ALIGN: usize = 8;

/// One camera's refinement state: an opaque value the caller allocates and
/// `caveclod_camera_init` fills; its state lives in caller memory. It holds nothing to free:
/// forget it, then free its memory. Never copy an initialised camera (both copies would
/// change the same memory); one camera belongs to one thread at a time.
#[repr(C)]
pub struct CaveclodCamera {
    opaque: [u64; CAVECLOD_CAMERA_WORDS],
}

/// What a camera handle holds.
pub(crate) struct Camera {
    pub state: CameraState<'static>,
    /// The per-surface slice table in the camera's memory, `surfaces` entries.
    pub lists: *mut &'static mut [u32],
    pub surfaces: usize,
}

pub(crate) const CAMERA_TAG: u64 = u64::from_le_bytes(*b"ccldCamr");

const _: () = assert!(
    ffi::fits::<CaveclodCamera, Camera>()
        && core::mem::align_of::<&mut [u32]>() <= CAVECLOD_MEMORY_ALIGN
);

/// The camera of an initialised handle.
///
/// # Safety
/// `cam` is null or points to a `CaveclodCamera` nothing else uses during the call.
pub(crate) unsafe fn camera<'a>(cam: *mut CaveclodCamera) -> Result<&'a mut Camera> {
    // SAFETY: the caller's contract.
    unsafe { ffi::handle_mut(cam, CAMERA_TAG) }
}

/// The camera of an initialised handle, checked to belong to `h`.
///
/// # Safety
/// As [`camera`].
pub(crate) unsafe fn camera_for<'a>(
    cam: *mut CaveclodCamera,
    h: &impl HierarchyRecords,
) -> Result<&'a mut Camera> {
    // SAFETY: the caller's contract.
    let cam = unsafe { camera(cam) }?;
    if cam.state.is_for(h) {
        Ok(cam)
    } else {
        Err(CaveclodStatus::WrongHierarchy)
    }
}

/// The layout of a camera's memory: bytes of the state words, bytes in all.
struct MemoryLayout {
    words: usize,
    state_bytes: usize,
    total_bytes: usize,
}

fn memory_layout(h: &impl HierarchyRecords, config: &CameraConfig) -> Result<MemoryLayout> {
    let words = CameraState::words_needed_for(h, config);
    let state_bytes = words
        .checked_mul(4)
        .and_then(|b| b.checked_next_multiple_of(CAVECLOD_MEMORY_ALIGN))
        .ok_or(CaveclodStatus::InvalidConfig)?;
    let table = h
        .surface_count()
        .checked_mul(core::mem::size_of::<&mut [u32]>())
        .ok_or(CaveclodStatus::InvalidConfig)?;
    let total_bytes = state_bytes
        .checked_add(table)
        .ok_or(CaveclodStatus::InvalidConfig)?;
    Ok(MemoryLayout {
        words,
        state_bytes,
        total_bytes,
    })
}

/// Fills `out` with the configuration of a camera that can reach full resolution anywhere.
///
/// Thread-safety: any thread, concurrently with any call that reads `h`.
///
/// # Safety
/// `h` is null or an opened hierarchy; `out` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_config_full(
    h: *const CaveclodHierarchy,
    out: *mut CaveclodCameraConfig,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let h = unsafe { hierarchy(h) }?;
        // SAFETY: the caller's contract.
        unsafe { ffi::output(out, CameraConfig::full(h).into()) }
    })
}

/// Fills `out` with the configuration of a camera of at most `max_active_polygons` active
/// polygons (at least the base mesh): a hard polygon budget, since a full camera refuses
/// further splits (counted in `capacity_refusals`) instead of failing.
///
/// Thread-safety: any thread, concurrently with any call that reads `h`.
///
/// # Safety
/// `h` is null or an opened hierarchy; `out` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_config_polygon_budget(
    h: *const CaveclodHierarchy,
    max_active_polygons: u32,
    out: *mut CaveclodCameraConfig,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let h = unsafe { hierarchy(h) }?;
        let config = CameraConfig::with_polygon_budget(h, max_active_polygons);
        // SAFETY: the caller's contract.
        unsafe { ffi::output(out, config.into()) }
    })
}

/// Writes to `*bytes` the memory a camera with `config` over `h` needs (aligned to
/// `CAVECLOD_MEMORY_ALIGN`). `CAVECLOD_STATUS_INVALID_CONFIG` when `config` asks for more
/// splits than `h` has, or more morphs than 32-bit indices can name.
///
/// Thread-safety: any thread, concurrently with any call that reads `h`.
///
/// # Safety
/// `h` is null or an opened hierarchy; `config` is null or readable; `bytes` is null or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_memory_size(
    h: *const CaveclodHierarchy,
    config: *const CaveclodCameraConfig,
    bytes: *mut usize,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let h = unsafe { hierarchy(h) }?;
        // SAFETY: the caller's contract.
        let config = unsafe { ffi::input(config) }?.to_config(h)?;
        // SAFETY: the caller's contract.
        unsafe { camera_memory_size(h, &config, bytes) }
    })
}

/// Writes the memory a camera with `config` over `h` needs to `bytes`.
///
/// # Safety
/// `bytes` is null or writable.
pub(crate) unsafe fn camera_memory_size(
    h: &impl HierarchyRecords,
    config: &CameraConfig,
    bytes: *mut usize,
) -> Result<()> {
    let layout = memory_layout(h, config)?;
    // SAFETY: the caller's contract.
    unsafe { ffi::output(bytes, layout.total_bytes) }
}

/// Makes `out` a camera at the base mesh of `h`, with `config`'s capacity, in
/// `memory[0..bytes]` (at least `caveclod_camera_memory_size` bytes, aligned to
/// `CAVECLOD_MEMORY_ALIGN`; the memory may be uninitialised). Allocates nothing.
///
/// Returns `CAVECLOD_STATUS_NULL_POINTER`, `CAVECLOD_STATUS_MISALIGNED` (for `memory`),
/// `CAVECLOD_STATUS_MEMORY_TOO_SMALL`, `CAVECLOD_STATUS_INVALID_CONFIG`, or
/// `CAVECLOD_STATUS_INVALID_HANDLE` for an unopened `h`. On failure `out` is left a handle
/// every other call refuses.
///
/// Thread-safety: any thread, concurrently with any call that reads `h`; `out` and `memory`
/// must not be used by another thread during the call.
///
/// # Safety
/// `memory` is null or valid for reads and writes of `bytes` bytes that nothing else uses
/// while the camera is in use; `h`'s file bytes outlive the camera; `out` is null or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_init(
    h: *const CaveclodHierarchy,
    config: *const CaveclodCameraConfig,
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
        let config = unsafe { ffi::input(config) }?.to_config(h)?;
        // SAFETY: the caller's contract.
        unsafe { init_camera(h, &config, memory, bytes, out) }
    })
}

/// Makes `out` (its tag cleared) a camera at the base mesh of `h` with `config`, in
/// `memory[0..bytes]`.
///
/// # Safety
/// As `caveclod_camera_init`'s; `out` is non-null, aligned and writable.
pub(crate) unsafe fn init_camera(
    h: &impl HierarchyRecords,
    config: &CameraConfig,
    memory: *mut core::ffi::c_void,
    bytes: usize,
    out: *mut CaveclodCamera,
) -> Result<()> {
    let layout = memory_layout(h, config)?;
    let base = ffi::caller_memory(memory, CAVECLOD_MEMORY_ALIGN, bytes, layout.total_bytes)?;
    // SAFETY: `memory` is valid for `bytes >= total_bytes` bytes; zeroing the state words
    // first makes every `u32` of the slice below initialised.
    unsafe { base.write_bytes(0, layout.state_bytes) };
    // SAFETY: aligned (to 8, so to 4), initialised, `words * 4 <= state_bytes` bytes, used
    // only through this camera while it lives (the caller's contract, which is what
    // `'static` stands for here).
    let words: &'static mut [u32] =
        unsafe { core::slice::from_raw_parts_mut(base.cast::<u32>(), layout.words) };
    let state = CameraState::with_config(h, words, config)?;
    // SAFETY: `state_bytes <= total_bytes <= bytes`; the table starts at a multiple of
    // `CAVECLOD_MEMORY_ALIGN`, enough for slices (asserted).
    let lists = unsafe { base.add(layout.state_bytes) }.cast::<&'static mut [u32]>();
    let camera = Camera {
        state,
        lists,
        surfaces: h.surface_count(),
    };
    // SAFETY: `out` is writable and the blob holds a `Cell<Camera>` (asserted).
    unsafe { ffi::fill(out, CAMERA_TAG, camera) };
    Ok(())
}

/// Puts the camera back at the base mesh of `h` (and ends its morphs).
///
/// Thread-safety: the thread that owns `cam`, concurrently with any call that reads `h`.
///
/// # Safety
/// `cam` is null or a camera nothing else uses during the call; `h` is null or an opened
/// hierarchy.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_reset(
    cam: *mut CaveclodCamera,
    h: *const CaveclodHierarchy,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let h = unsafe { hierarchy(h) }?;
        // SAFETY: the caller's contract.
        let cam = unsafe { camera_for(cam, h) }?;
        cam.state.reset(h);
        Ok(())
    })
}

/// Fills `out` with the default refinement parameters: 1 pixel, no operation cap, frustum
/// and back-face culling, 1/60 s per pass, Hoppe's morph durations.
///
/// Thread-safety: any thread.
///
/// # Safety
/// `out` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_refine_params_default(
    out: *mut CaveclodRefineParams,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        unsafe { ffi::output(out, RefineParams::default().into()) }
    })
}

/// One refinement pass of `cam` against `view`: splits where the projected error exceeds
/// the tolerance, collapses where it no longer does, steps the morphs. Allocates nothing;
/// work is proportional to the active front. Writes what it did to `stats` unless that is
/// null. A `params` of null means the defaults.
///
/// Returns `CAVECLOD_STATUS_WRONG_HIERARCHY` for a camera of another hierarchy,
/// `CAVECLOD_STATUS_INVALID_ARGUMENT` for a view or parameters out of range, and
/// `CAVECLOD_STATUS_INCONSISTENT` when the data contradicts the camera (reset it).
///
/// Thread-safety: the thread that owns `cam`; any number of cameras refine over one `h` on
/// as many threads at once.
///
/// # Safety
/// `cam` is null or a camera nothing else uses during the call; `h` is null or an opened
/// hierarchy; `view` and `params` are null or readable; `stats` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_refine(
    cam: *mut CaveclodCamera,
    h: *const CaveclodHierarchy,
    view: *const CaveclodView,
    params: *const CaveclodRefineParams,
    stats: *mut CaveclodRefineStats,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let h = unsafe { hierarchy(h) }?;
        // SAFETY: the caller's contract.
        let cam = unsafe { camera_for(cam, h) }?;
        // SAFETY: the caller's contract.
        unsafe { refine_camera(cam, h, view, params, stats) }.map(|_| ())
    })
}

/// One refinement pass of `cam` over `h` (see `caveclod_camera_refine`); the splits that
/// waited for absent pages.
///
/// # Safety
/// `view` and `params` are null or readable; `stats` is null or writable.
pub(crate) unsafe fn refine_camera(
    cam: &mut Camera,
    h: &impl HierarchyRecords,
    view: *const CaveclodView,
    params: *const CaveclodRefineParams,
    stats: *mut CaveclodRefineStats,
) -> Result<u32> {
    // SAFETY: the caller's contract.
    let view = unsafe { ffi::input(view) }?.to_view()?;
    let params = if params.is_null() {
        RefineParams::default()
    } else {
        // SAFETY: the caller's contract.
        unsafe { ffi::input(params) }?.to_params()
    };
    let s = cam.state.refine(h, &view, &params)?;
    // SAFETY: the caller's contract.
    unsafe { ffi::optional_output(stats, s.into()) }?;
    Ok(s.deferred_splits)
}

/// Writes the camera's counts to `out`: active nodes and polygons, splits, morphs, and the
/// total index count packed emission needs.
///
/// Thread-safety: the thread that owns `cam`.
///
/// # Safety
/// `cam` is null or a camera nothing else uses during the call; `out` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_counts(
    cam: *mut CaveclodCamera,
    out: *mut CaveclodCameraCounts,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let s = &unsafe { camera(cam) }?.state;
        let counts = CaveclodCameraCounts {
            active_nodes: s.active_node_count(),
            active_polygons: s.active_polygon_count(),
            splits: s.split_count(),
            max_pairs: s.max_pairs(),
            morphs: s.morph_count(),
            max_morphs: s.max_morphs(),
            total_indices: s.total_index_count() as u64,
        };
        // SAFETY: the caller's contract.
        unsafe { ffi::output(out, counts) }
    })
}
