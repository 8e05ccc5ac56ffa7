//! Index edits over a streamed file through the C ABI: a camera over a
//! `CaveclodStreamedFile` that keeps each polygon's place in a device index buffer, whose
//! edits name vertices in the pool's device vertex pool when it has one.

use crate::camera::{camera_for, CaveclodCamera};
use crate::ffi::{self, guarded};
use crate::index_edits::{
    edited_config, write_edits, CaveclodIndexEdit, CaveclodIndexEdits, CaveclodSurfaceDraw,
};
use crate::status::CaveclodStatus;
use crate::streamed::{init_over, memory_size_over, records, CaveclodStreamedFile};
use crate::types::CaveclodCameraConfig;

/// `caveclod_camera_memory_size_edited` for a camera over the streamed file `f`.
///
/// Thread-safety: the thread that owns `f`'s lists, while nothing changes the pool.
///
/// # Safety
/// `f` is null or a readable `CaveclodStreamedFile` of initialised handles; `config` is null
/// or readable; `bytes` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_memory_size_edited_streamed(
    f: *const CaveclodStreamedFile,
    config: *const CaveclodCameraConfig,
    edit_list: u32,
    bytes: *mut usize,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let config = unsafe { ffi::input(config) }?;
        // SAFETY: the caller's contract.
        unsafe { memory_size_over(f, |h| edited_config(h, config, edit_list), bytes) }
    })
}

/// `caveclod_camera_init_edited` for a camera over the streamed file `f`, at its base mesh.
///
/// Thread-safety: the thread that owns `f`'s lists, while nothing changes the pool; `out`
/// and `memory` must not be used by another thread during the call.
///
/// # Safety
/// As `caveclod_camera_init_streamed`'s.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_init_edited_streamed(
    f: *const CaveclodStreamedFile,
    config: *const CaveclodCameraConfig,
    edit_list: u32,
    memory: *mut core::ffi::c_void,
    bytes: usize,
    out: *mut CaveclodCamera,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let config = unsafe { ffi::input(config) }?;
        // SAFETY: the caller's contract.
        unsafe {
            init_over(
                f,
                |h| edited_config(h, config, edit_list),
                memory,
                bytes,
                out,
            )
        }
    })
}

/// `caveclod_camera_index_edits` for a camera over the streamed file `f`: with a device
/// vertex pool beside `f`'s pool, the edits' indices name its places.
///
/// Thread-safety: the thread that owns `cam` and `f`'s lists, while nothing changes the
/// pool.
///
/// # Safety
/// As `caveclod_camera_index_edits`'s, with `f` a readable `CaveclodStreamedFile` of
/// initialised handles.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_index_edits_streamed(
    cam: *mut CaveclodCamera,
    f: *const CaveclodStreamedFile,
    max_moves: u32,
    out: *mut CaveclodIndexEdit,
    capacity: usize,
    draws: *mut CaveclodSurfaceDraw,
    draw_count: usize,
    result: *mut CaveclodIndexEdits,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let h = unsafe { records(f) }?;
        // SAFETY: the caller's contract.
        let cam = unsafe { camera_for(cam, &h) }?;
        // SAFETY: the caller's contract.
        unsafe {
            write_edits(
                cam,
                &h,
                max_moves,
                (out, capacity),
                (draws, draw_count),
                result,
            )
        }
    })
}
