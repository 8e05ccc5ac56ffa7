//! A device vertex pool beside a page pool (the core's `VertexPoolLayout`): where a resident
//! page's vertices go in the host's vertex buffer, the roots' once, and a streamed camera's
//! morph slots as the device reads them.

use caveclod_core::stream::{PageKey, VertexInstall};

use crate::camera::{camera_for, CaveclodCamera};
use crate::emit::CaveclodMorphVertex;
use crate::ffi::{self, guarded};
use crate::paged_root::{paged_root, CaveclodPagedRoot};
use crate::pool::{pool_ref, CaveclodPool};
use crate::status::CaveclodStatus;
use crate::streamed::{records, CaveclodStreamedFile};

/// Vertices to copy into the device vertex pool: `count` of them from `vertices` to places
/// `first..first + count`, and their colours from `colours` if the page has them.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CaveclodVertexInstall {
    /// The device pool index of the first vertex.
    pub first: u32,
    /// Vertices.
    pub count: u32,
    /// `count` vertices of 32 bytes (position, normal, uv), in the pool's bytes (for a page:
    /// valid until the pool reuses its slot) or the root's.
    pub vertices: *const core::ffi::c_void,
    /// `count` RGBA8 colours (sRGB colour, linear alpha), or null.
    pub colours: *const core::ffi::c_void,
}

impl From<VertexInstall<'_>> for CaveclodVertexInstall {
    fn from(i: VertexInstall<'_>) -> Self {
        Self {
            first: i.first,
            count: i.vertices.len() as u32,
            vertices: i.vertices.as_ptr().cast(),
            colours: i.colours.map_or(core::ptr::null(), |c| c.as_ptr().cast()),
        }
    }
}

/// Writes to `out` the vertices of page (`file`, `page`), streamed and resident in pool `p`,
/// and where they go in its device vertex pool: copy them there before a frame's fronts may
/// use the page (in the frame that installed it). `CAVECLOD_STATUS_INVALID_ARGUMENT` without
/// a vertex pool (`slot_vertices` 0) or for a page that is not streamed and resident.
///
/// Thread-safety: any thread, while nothing changes the pool.
///
/// # Safety
/// `p` is null or an initialised pool nothing writes during the call; `out` is null or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_pool_page_vertices(
    p: *const CaveclodPool,
    file: u32,
    page: u32,
    out: *mut CaveclodVertexInstall,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let p = unsafe { pool_ref(p) }?;
        let install = p
            .page_vertices(PageKey { file, page })
            .ok_or(CaveclodStatus::InvalidArgument)?;
        // SAFETY: the caller's contract.
        unsafe { ffi::output(out, install.into()) }
    })
}

/// Writes to `out` the vertices of root page `page` of file `file` (whose root is `r`) and
/// where they go in pool `p`'s device vertex pool: copy every root page's once, when the
/// pool is made. `CAVECLOD_STATUS_INVALID_ARGUMENT` without a vertex pool or for a page
/// that is not one of the file's root pages.
///
/// Thread-safety: any thread, while nothing changes the pool.
///
/// # Safety
/// `p` is null or an initialised pool nothing writes during the call; `r` is null or the
/// opened root of file `file`; `out` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_pool_root_vertices(
    p: *const CaveclodPool,
    r: *const CaveclodPagedRoot,
    file: u32,
    page: u32,
    out: *mut CaveclodVertexInstall,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let (p, r) = unsafe { (pool_ref(p)?, paged_root(r)?) };
        let install = p
            .root_vertices(file, r, page)
            .ok_or(CaveclodStatus::InvalidArgument)?;
        // SAFETY: the caller's contract.
        unsafe { ffi::output(out, install.into()) }
    })
}

/// Writes the morph slots of `cam` over the streamed file `f` as the device reads them
/// (every vertex at its place in the device vertex pool, a chained `from` past the pool's
/// vertices) to `out[0..n]` and `n` to `written`; `CAVECLOD_STATUS_OUTPUT_TOO_SMALL` if
/// `capacity` is less than the slots in use.
///
/// Thread-safety: the thread that owns `cam` and `f`'s lists, while nothing changes the
/// pool.
///
/// # Safety
/// `cam` is null or a camera over `f` nothing else uses during the call; `f` is null or a
/// readable `CaveclodStreamedFile` of initialised handles; `out` is null or writable for
/// `capacity` records; `written` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_device_morph_vertices_streamed(
    cam: *mut CaveclodCamera,
    f: *const CaveclodStreamedFile,
    out: *mut CaveclodMorphVertex,
    capacity: usize,
    written: *mut usize,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let h = unsafe { records(f) }?;
        // SAFETY: the caller's contract.
        let cam = unsafe { camera_for(cam, &h) }?;
        // SAFETY: the caller's contract; `CaveclodMorphVertex` has `MorphVertex`'s layout
        // (both `repr(C)`, the same four 32-bit fields; asserted where it is declared).
        let out = unsafe { ffi::slice_mut(out.cast(), capacity) }?;
        let n = cam
            .state
            .device_morph_vertices(&h, out)
            .map_err(CaveclodStatus::from)?;
        // SAFETY: the caller's contract.
        unsafe { ffi::output(written, n) }
    })
}
