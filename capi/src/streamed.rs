//! Cameras over paged files from C: a frame's lists (what refinement over the pool wants
//! and which pages the fronts stand on), `caveclod_pool_apply` to hand them to the pool, and
//! the camera calls over one file's streamed records ([`CaveclodStreamedFile`]: its root,
//! the pool, the file's index there, the frame's lists).
//!
//! A frame: `caveclod_pool_begin_frame`; each camera refines over each file with
//! `caveclod_camera_refine_streamed` (splits whose pages are absent wait, and their pages go
//! into the lists); `caveclod_pool_apply`; then `caveclod_pool_schedule`, the reads, and
//! `caveclod_pool_install` or `caveclod_pool_fail`. The pool must not change while cameras
//! refine over it: apply, schedule, install and fail come after every camera's call.

use caveclod_core::format::paged::PagedRoot;
use caveclod_core::stream::{
    FrameLists, PageKey, PoolConfig, Pressure, PressureSignal, ScheduleStats, StreamedHierarchy,
    Want,
};
use caveclod_core::CameraConfig;

use crate::camera::{
    camera_for, camera_memory_size, init_camera, refine_camera, CaveclodCamera,
    CAVECLOD_MEMORY_ALIGN,
};
use crate::emit::{emit_packed, PackedOut};
use crate::ffi::{self, guarded, Result};
use crate::paged_root::{paged_root, CaveclodPagedRoot};
use crate::pool::{pool, pool_ref, CaveclodPool, CaveclodScheduleStats, Pool};
use crate::status::CaveclodStatus;
use crate::types::{CaveclodCameraConfig, CaveclodRefineParams, CaveclodRefineStats, CaveclodView};

/// Words (of 8 bytes) of a `CaveclodFrameLists`.
pub const CAVECLOD_FRAME_LISTS_WORDS: usize = 32;

/// A frame's lists for one thread's cameras: an opaque value `caveclod_frame_lists_init`
/// fills, over memory the caller sizes with `caveclod_frame_lists_memory_size`.
#[repr(C)]
pub struct CaveclodFrameLists {
    opaque: [u64; CAVECLOD_FRAME_LISTS_WORDS],
}

type Lists = FrameLists<'static>;

const LISTS_TAG: u64 = u64::from_le_bytes(*b"ccldList");

const _: () = assert!(
    ffi::fits::<CaveclodFrameLists, Lists>()
        && core::mem::align_of::<Want>() <= CAVECLOD_MEMORY_ALIGN
);

/// One paged file's records as cameras read them: its root, the pool serving it, its index
/// there (as `caveclod_pool_add_file` numbered it), and the frame's lists.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CaveclodStreamedFile {
    /// The file's root.
    pub root: *const CaveclodPagedRoot,
    /// The pool serving its pages.
    pub pool: *const CaveclodPool,
    /// The file's index in the pool.
    pub file: u32,
    /// The frame's lists, which the calls write to.
    pub lists: *mut CaveclodFrameLists,
}

/// What refinement over streamed files read and asked for, since the lists were made.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CaveclodStreamedReads {
    /// Wants listed.
    pub wanted: u32,
    /// Wants that did not fit the lists (asked again by a later frame).
    pub wants_dropped: u32,
    /// Front nodes that joined or left in a page that is not resident (stays 0).
    pub untracked_uses: u32,
    /// Zero.
    pub reserved: u32,
    /// Reads of a record in a page that is not resident (stays 0).
    pub absent_reads: u64,
}

/// The lists of an initialised handle.
///
/// # Safety
/// `l` is null or points to a `CaveclodFrameLists` nothing else uses during `'a`.
unsafe fn lists<'a>(l: *mut CaveclodFrameLists) -> Result<&'a mut Lists> {
    // SAFETY: the caller's contract.
    unsafe { ffi::handle_mut(l, LISTS_TAG) }
}

/// The memory of lists for `config` with room for `max_wants` wants: the wants, then the
/// words; its size in bytes.
fn lists_layout(config: &PoolConfig, max_wants: u32) -> Result<(usize, usize)> {
    let wants = (max_wants as usize)
        .checked_mul(core::mem::size_of::<Want>())
        .and_then(|b| b.checked_next_multiple_of(CAVECLOD_MEMORY_ALIGN))
        .ok_or(CaveclodStatus::InvalidConfig)?;
    let words = FrameLists::words_needed(config)
        .checked_mul(4)
        .ok_or(CaveclodStatus::InvalidConfig)?;
    let total = wants
        .checked_add(words)
        .ok_or(CaveclodStatus::InvalidConfig)?;
    Ok((wants, total))
}

/// Writes to `bytes` how much memory (aligned to `CAVECLOD_MEMORY_ALIGN`) a frame's lists
/// for `pool` with room for `max_wants` wanted pages need.
///
/// Thread-safety: any thread, while nothing changes `pool`.
///
/// # Safety
/// `pool` is null or an initialised pool; `bytes` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_frame_lists_memory_size(
    pool: *const CaveclodPool,
    max_wants: u32,
    bytes: *mut usize,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let pool = unsafe { pool_ref(pool) }?;
        let (_, total) = lists_layout(pool.config(), max_wants)?;
        // SAFETY: the caller's contract.
        unsafe { ffi::output(bytes, total) }
    })
}

/// Makes `out` empty lists for `pool` in `memory[0..bytes]` (at least
/// `caveclod_frame_lists_memory_size`, aligned to `CAVECLOD_MEMORY_ALIGN`, may be
/// uninitialised). Allocates nothing. Give each thread that refines its own lists.
///
/// Thread-safety: any thread, while nothing changes `pool`.
///
/// # Safety
/// `pool` is null or an initialised pool; `memory` is null or valid for reads and writes of
/// `bytes` bytes that nothing else uses while the lists are in use; `out` is null or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_frame_lists_init(
    pool: *const CaveclodPool,
    max_wants: u32,
    memory: *mut core::ffi::c_void,
    bytes: usize,
    out: *mut CaveclodFrameLists,
) -> CaveclodStatus {
    guarded(|| {
        let out = ffi::checked(out.cast_const())?.cast_mut();
        // SAFETY: `out` is non-null, aligned and writable (the caller's contract).
        unsafe { ffi::clear_tag::<_, Lists>(out) };
        // SAFETY: the caller's contract.
        let config = *unsafe { pool_ref(pool) }?.config();
        let (wants_bytes, total) = lists_layout(&config, max_wants)?;
        let base = ffi::caller_memory(memory, CAVECLOD_MEMORY_ALIGN, bytes, total)?;
        let wants = base.cast::<Want>();
        for i in 0..max_wants as usize {
            // SAFETY: `wants_bytes` bytes at `base` hold `max_wants` wants, aligned (asserted).
            unsafe { wants.add(i).write(Want::default()) };
        }
        // SAFETY: initialised above; used only through these lists while they live (the
        // caller's contract, which is what `'static` stands for here).
        let wants: &'static mut [Want] =
            unsafe { core::slice::from_raw_parts_mut(wants, max_wants as usize) };
        let words_len = FrameLists::words_needed(&config);
        // SAFETY: `wants_bytes + 4 * words_len <= bytes`, the words start on 8 bytes; zeroed
        // before the slice is made, so every `u32` is initialised.
        let words: &'static mut [u32] = unsafe {
            let w = base.add(wants_bytes).cast::<u32>();
            w.write_bytes(0, words_len);
            core::slice::from_raw_parts_mut(w, words_len)
        };
        let lists =
            FrameLists::new(&config, wants, words).map_err(|_| CaveclodStatus::MemoryTooSmall)?;
        // SAFETY: `out` is writable and the blob holds a `Cell<Lists>` (asserted).
        unsafe { ffi::fill(out, LISTS_TAG, lists) };
        Ok(())
    })
}

/// Writes to `out` what refinement over streamed files read and asked for through `lists`.
///
/// Thread-safety: the thread that owns `lists`.
///
/// # Safety
/// `lists` is null or initialised lists nothing else uses during the call; `out` is null or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_frame_lists_reads(
    lists: *mut CaveclodFrameLists,
    out: *mut CaveclodStreamedReads,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let r = unsafe { self::lists(lists) }?.reads();
        let reads = CaveclodStreamedReads {
            wanted: r.wanted,
            wants_dropped: r.wants_dropped,
            untracked_uses: r.untracked_uses,
            reserved: 0,
            absent_reads: r.absent_reads,
        };
        // SAFETY: the caller's contract.
        unsafe { ffi::output(out, reads) }
    })
}

/// Hands the frame's lists to the pool, after every camera refined over it and before
/// `caveclod_pool_schedule`: the wanted pages are requested, and each page's count of the
/// front nodes standing on it moves (a page a front stands on is never evicted). The lists
/// are empty again.
///
/// Thread-safety: the thread that owns the pool, while no camera refines over it.
///
/// # Safety
/// `pool` and `lists` are null or initialised, and nothing else uses them during the call.
#[no_mangle]
pub unsafe extern "C" fn caveclod_pool_apply(
    pool: *mut CaveclodPool,
    lists: *mut CaveclodFrameLists,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let lists = unsafe { self::lists(lists) }?;
        // SAFETY: the caller's contract.
        let pool = unsafe { self::pool(pool) }?;
        pool.apply(lists).map_err(|_| CaveclodStatus::Inconsistent)
    })
}

/// What `f` names: the root, the pool, the file's index there and the lists, checked to
/// agree (the pool serves the file with the root's page count).
///
/// # Safety
/// `f` is null or readable, and names an opened root, an initialised pool nothing changes
/// during `'a`, and initialised lists nothing else uses during `'a`.
unsafe fn parts<'a>(
    f: *const CaveclodStreamedFile,
) -> Result<(&'a PagedRoot<'static>, &'a Pool, u32, &'a mut Lists)> {
    // SAFETY: the caller's contract.
    let f = unsafe { ffi::input(f) }?;
    // SAFETY: the caller's contract.
    let root = unsafe { paged_root(f.root) }?;
    // SAFETY: the caller's contract.
    let pool = unsafe { pool_ref(f.pool) }?;
    // SAFETY: the caller's contract.
    let lists = unsafe { lists(f.lists) }?;
    let pages = root.table().len() as u32;
    let key = |page| PageKey { file: f.file, page };
    if pool.state(key(pages.saturating_sub(1))).is_none() || pool.state(key(pages)).is_some() {
        return Err(CaveclodStatus::WrongHierarchy);
    }
    Ok((root, pool, f.file, lists))
}

/// The records `f` names for this call: its root and the pages resident in its pool, what
/// the cameras want going to its lists.
///
/// # Safety
/// As [`parts`].
pub(crate) unsafe fn records<'a>(
    f: *const CaveclodStreamedFile,
) -> Result<StreamedHierarchy<'a, 'a, 'static, 'static>> {
    // SAFETY: the caller's contract.
    let (root, pool, file, lists) = unsafe { parts(f) }?;
    Ok(StreamedHierarchy::new(root, pool, file, lists))
}

/// Writes to `bytes` the memory a camera over `f` needs, its configuration made by `config`
/// over `f`'s records.
///
/// # Safety
/// As [`parts`]; `bytes` is null or writable.
pub(crate) unsafe fn memory_size_over(
    f: *const CaveclodStreamedFile,
    config: impl FnOnce(&StreamedHierarchy<'_, '_, '_, '_>) -> Result<CameraConfig>,
    bytes: *mut usize,
) -> Result<()> {
    // SAFETY: the caller's contract.
    let h = unsafe { records(f) }?;
    let config = config(&h)?;
    // SAFETY: the caller's contract.
    unsafe { camera_memory_size(&h, &config, bytes) }
}

/// Makes `out` a camera over `f` in `memory`, its configuration made by `config` over
/// `f`'s records; `out` is left a handle every other call refuses if that fails.
///
/// # Safety
/// As `caveclod_camera_init_streamed`'s.
pub(crate) unsafe fn init_over(
    f: *const CaveclodStreamedFile,
    config: impl FnOnce(&StreamedHierarchy<'_, '_, '_, '_>) -> Result<CameraConfig>,
    memory: *mut core::ffi::c_void,
    bytes: usize,
    out: *mut CaveclodCamera,
) -> Result<()> {
    let out = ffi::checked(out.cast_const())?.cast_mut();
    // SAFETY: `out` is non-null, aligned and writable (the caller's contract).
    unsafe { ffi::clear_tag::<_, crate::camera::Camera>(out) };
    // SAFETY: the caller's contract.
    let h = unsafe { records(f) }?;
    let config = config(&h)?;
    // SAFETY: the caller's contract.
    unsafe { init_camera(&h, &config, memory, bytes, out) }
}

/// `caveclod_camera_config_polygon_budget` for a camera over the streamed file `f`.
///
/// Thread-safety: the thread that owns `f`'s lists, while nothing changes the pool.
///
/// # Safety
/// `f` is null or a readable `CaveclodStreamedFile` of initialised handles; `out` is null or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_config_polygon_budget_streamed(
    f: *const CaveclodStreamedFile,
    max_active_polygons: u32,
    out: *mut CaveclodCameraConfig,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let h = unsafe { records(f) }?;
        let config = CameraConfig::with_polygon_budget(&h, max_active_polygons);
        // SAFETY: the caller's contract.
        unsafe { ffi::output(out, config.into()) }
    })
}

/// `caveclod_camera_memory_size` for a camera over the streamed file `f`: its memory follows
/// `config`'s capacity, not the file's size.
///
/// Thread-safety: the thread that owns `f`'s lists, while nothing changes the pool.
///
/// # Safety
/// `f` is null or a readable `CaveclodStreamedFile` of initialised handles; `config` is null
/// or readable; `bytes` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_memory_size_streamed(
    f: *const CaveclodStreamedFile,
    config: *const CaveclodCameraConfig,
    bytes: *mut usize,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let config = unsafe { ffi::input(config) }?;
        // SAFETY: the caller's contract.
        unsafe { memory_size_over(f, |h| config.to_config(h), bytes) }
    })
}

/// `caveclod_camera_init` for a camera over the streamed file `f`, at its base mesh (which
/// lies in the root).
///
/// Thread-safety: the thread that owns `f`'s lists, while nothing changes the pool; `out`
/// and `memory` must not be used by another thread during the call.
///
/// # Safety
/// As `caveclod_camera_init`'s, with `f` a readable `CaveclodStreamedFile` of initialised
/// handles whose root's bytes outlive the camera.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_init_streamed(
    f: *const CaveclodStreamedFile,
    config: *const CaveclodCameraConfig,
    memory: *mut core::ffi::c_void,
    bytes: usize,
    out: *mut CaveclodCamera,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let config = unsafe { ffi::input(config) }?;
        // SAFETY: the caller's contract.
        unsafe { init_over(f, |h| config.to_config(h), memory, bytes, out) }
    })
}

/// `caveclod_camera_refine` over the streamed file `f`: a split whose records lie in an
/// absent page waits (counted in `*deferred_splits` unless that is null) and its page goes
/// into the lists with the split's screen-space error excess; the camera shows the coarser
/// surface until the page arrives. Nothing reads an absent page.
///
/// Thread-safety: the thread that owns `cam` and `f`'s lists; cameras on several threads
/// refine over one pool at once, each thread with its own lists, while nothing changes it.
///
/// # Safety
/// `cam` is null or a camera nothing else uses during the call; `f` is null or a readable
/// `CaveclodStreamedFile` of initialised handles; `view` and `params` are null or readable;
/// `stats` and `deferred_splits` are null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_refine_streamed(
    cam: *mut CaveclodCamera,
    f: *const CaveclodStreamedFile,
    view: *const CaveclodView,
    params: *const CaveclodRefineParams,
    stats: *mut CaveclodRefineStats,
    deferred_splits: *mut u32,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let h = unsafe { records(f) }?;
        // SAFETY: the caller's contract.
        let cam = unsafe { camera_for(cam, &h) }?;
        // SAFETY: the caller's contract.
        let deferred = unsafe { refine_camera(cam, &h, view, params, stats) }?;
        // SAFETY: the caller's contract.
        unsafe { ffi::optional_output(deferred_splits, deferred) }
    })
}

/// `caveclod_camera_reset` over the streamed file `f`: the front goes back to the base mesh
/// and leaves every streamed page (apply the lists before dropping the camera).
///
/// Thread-safety: as `caveclod_camera_refine_streamed`.
///
/// # Safety
/// `cam` is null or a camera nothing else uses during the call; `f` is null or a readable
/// `CaveclodStreamedFile` of initialised handles.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_reset_streamed(
    cam: *mut CaveclodCamera,
    f: *const CaveclodStreamedFile,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let h = unsafe { records(f) }?;
        // SAFETY: the caller's contract.
        let cam = unsafe { camera_for(cam, &h) }?;
        cam.state.reset(&h);
        Ok(())
    })
}

/// `caveclod_camera_emit_packed` over the streamed file `f`. Indices name vertices by their
/// page-major ids (`(page << page_bits) | index`), which a host drawing from a vertex pool
/// maps to its own slots.
///
/// Thread-safety: as `caveclod_camera_refine_streamed`.
///
/// # Safety
/// As `caveclod_camera_emit_packed`'s, with `f` a readable `CaveclodStreamedFile` of
/// initialised handles.
#[no_mangle]
pub unsafe extern "C" fn caveclod_camera_emit_packed_streamed(
    cam: *mut CaveclodCamera,
    f: *const CaveclodStreamedFile,
    out: *mut u32,
    capacity: usize,
    offsets: *mut u32,
    offset_count: usize,
    morphed: bool,
    total: *mut usize,
) -> CaveclodStatus {
    guarded(|| {
        let o = PackedOut {
            out,
            capacity,
            offsets,
            offset_count,
            total,
        };
        // SAFETY: the caller's contract.
        let h = unsafe { records(f) }?;
        // SAFETY: the caller's contract.
        let cam = unsafe { camera_for(cam, &h) }?;
        // SAFETY: the caller's contract.
        unsafe { emit_packed(cam, &h, &o, morphed) }
    })
}

/// Words (of 8 bytes) of a `CaveclodPressure`.
pub const CAVECLOD_PRESSURE_WORDS: usize = 4;

/// One scale on the tolerance of every camera over a pool, raised while the pool is nearly
/// full or splits pile up while the reads fall behind, and lowered back to 1 when both ease
/// (the core's `stream::Pressure`): an opaque value `caveclod_pressure_init` fills.
#[repr(C)]
pub struct CaveclodPressure {
    opaque: [u64; CAVECLOD_PRESSURE_WORDS],
}

const PRESSURE_TAG: u64 = u64::from_le_bytes(*b"ccldPres");

const _: () = assert!(ffi::fits::<CaveclodPressure, Pressure>());

/// Makes `out` a pressure at scale 1 that may scale the tolerance up to `max_scale` (at
/// least 1; 1 never scales).
///
/// Thread-safety: any thread.
///
/// # Safety
/// `out` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_pressure_init(
    max_scale: f32,
    out: *mut CaveclodPressure,
) -> CaveclodStatus {
    guarded(|| {
        let out = ffi::checked(out.cast_const())?.cast_mut();
        // SAFETY: `out` is non-null, aligned and writable (the caller's contract), and the
        // blob holds a `Cell<Pressure>` (asserted).
        unsafe { ffi::fill(out, PRESSURE_TAG, Pressure::new().with_max_scale(max_scale)) };
        Ok(())
    })
}

/// After a frame's `caveclod_pool_schedule`: reads the pool's room, what `schedule` did, and
/// the frame's deferred splits and active nodes summed over the cameras; moves the scale and
/// writes it to `*scale`. Multiply every camera's `tolerance_px` by it next frame.
///
/// Thread-safety: the thread that owns the pool, while nothing changes it.
///
/// # Safety
/// `pressure` and `pool` are null or initialised; `schedule` is null or readable; `scale`
/// is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_pressure_update(
    pressure: *mut CaveclodPressure,
    pool: *const CaveclodPool,
    schedule: *const CaveclodScheduleStats,
    deferred_splits: u32,
    active_nodes: u32,
    scale: *mut f32,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let p: &mut Pressure = unsafe { ffi::handle_mut(pressure, PRESSURE_TAG) }?;
        // SAFETY: the caller's contract.
        let pool = unsafe { pool_ref(pool) }?;
        // SAFETY: the caller's contract.
        let schedule = unsafe { ffi::input(schedule) }?;
        let stats = ScheduleStats {
            waiting: schedule.waiting,
            ..ScheduleStats::default()
        };
        let signal = PressureSignal::new(
            pool.config().slots,
            &pool.stats(),
            &stats,
            deferred_splits,
            active_nodes,
        );
        let s = p.update(&signal);
        // SAFETY: the caller's contract.
        unsafe { ffi::optional_output(scale, s) }
    })
}
