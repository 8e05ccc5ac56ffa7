//! A page pool in caller memory: the core's `Residency` behind the two calls of streaming,
//! "load page P into slot S" (`caveclod_pool_schedule`) and "slot S holds these bytes"
//! (`caveclod_pool_install`) or "failed" (`caveclod_pool_fail`).

use caveclod_core::format::paged::PageTable;
use caveclod_core::stream::{
    FaultKind, InstallError, LoadRequest, PageFault, PageKey, PoolConfig, PoolError, Residency,
    ScheduleStats, VertexPoolLayout, Wanted,
};

use crate::camera::CAVECLOD_MEMORY_ALIGN;
use crate::ffi::{self, guarded, Result};
use crate::paged_root::{paged_root, CaveclodPagedRoot};
use crate::status::CaveclodStatus;

/// The most loads one `caveclod_pool_schedule` starts.
pub const CAVECLOD_MAX_LOADS: usize = 128;

/// Words (of 8 bytes) of a `CaveclodPool`.
pub const CAVECLOD_POOL_WORDS: usize = 64;

/// A page pool: an opaque value the caller places anywhere and `caveclod_pool_init` fills,
/// over memory the caller sizes with `caveclod_pool_memory_size` and the pool's bytes.
#[repr(C)]
pub struct CaveclodPool {
    opaque: [u64; CAVECLOD_POOL_WORDS],
}

pub(crate) type Pool = Residency<'static, 'static>;
type Table = Option<PageTable<'static>>;

const POOL_TAG: u64 = u64::from_le_bytes(*b"ccldPool");

const _: () = assert!(
    ffi::fits::<CaveclodPool, Pool>() && core::mem::align_of::<Table>() <= CAVECLOD_MEMORY_ALIGN
);

/// A pool's sizes (see the core's `PoolConfig`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CaveclodPoolConfig {
    /// Bytes a slot holds: a multiple of 64, at least every streamed page's size.
    pub slot_bytes: u32,
    /// Slots: the pool's bytes are `slots * slot_bytes`, 64-byte aligned.
    pub slots: u32,
    /// Files the pool may serve.
    pub files: u32,
    /// Pages over those files.
    pub pages: u32,
    /// Pages that may be wanted in one frame.
    pub max_requests: u32,
    /// Vertex places per slot of a device vertex pool beside the pool (at least the
    /// `most_page_vertices` of every file); 0: the pool feeds no device vertex pool, and
    /// index lists name vertices by their ids.
    pub slot_vertices: u32,
    /// The device vertex pool's vertices: `slots * slot_vertices` for the slots, then room
    /// for every file's `root_vertices`. Morph slots are numbered past them.
    pub vertex_pool_vertices: u32,
}

/// What `caveclod_pool_want` found.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CaveclodWanted {
    /// Resident: use it.
    Resident = 0,
    /// Loading or now requested: defer what needs it.
    Requested = 1,
    /// It failed: stay at the coarser level.
    Failed = 2,
    /// This frame's requests are full: ask again next frame.
    Dropped = 3,
}

/// A page of one of a pool's files.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CaveclodPageKey {
    /// The file, as `caveclod_pool_add_file` numbered it.
    pub file: u32,
    /// The page.
    pub page: u32,
}

/// "Load page (file, page) into slot `slot`": `size` bytes from `offset` of its file go to
/// `caveclod_pool_loading_slot(slot)`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CaveclodLoadRequest {
    /// The file.
    pub file: u32,
    /// The page.
    pub page: u32,
    /// The slot reserved for it.
    pub slot: u32,
    /// Its length in bytes.
    pub size: u32,
    /// Where its bytes start in its file.
    pub offset: u64,
}

/// What one `caveclod_pool_schedule` did.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CaveclodScheduleStats {
    /// Pages requested this frame, with the absent parents they need.
    pub requested: u32,
    /// Loads written.
    pub loads: u32,
    /// Pages evicted (written to `evicted`).
    pub evictions: u32,
    /// Loadable pages left for a later frame.
    pub waiting: u32,
    /// Requested pages waiting for a parent.
    pub blocked: u32,
    /// Requests past `max_requests`, dropped.
    pub dropped: u32,
}

/// A page that failed: it stays absent (`kind`: 1 unreadable, 2 checksum, 3 contents).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CaveclodPageFault {
    /// The file.
    pub file: u32,
    /// The page.
    pub page: u32,
    /// What failed.
    pub kind: u32,
    /// Zero.
    pub reserved: u32,
}

impl From<PageFault> for CaveclodPageFault {
    fn from(f: PageFault) -> Self {
        let kind = match f.kind {
            FaultKind::Io => 1,
            FaultKind::Checksum { .. } => 2,
            FaultKind::Content(_) => 3,
        };
        Self {
            file: f.key.file,
            page: f.key.page,
            kind,
            reserved: 0,
        }
    }
}

fn config_of(c: &CaveclodPoolConfig) -> PoolConfig {
    PoolConfig {
        slot_bytes: c.slot_bytes,
        slots: c.slots,
        files: c.files,
        pages: c.pages,
        max_requests: c.max_requests,
        vertex_pool: (c.slot_vertices > 0).then_some(VertexPoolLayout {
            slot_vertices: c.slot_vertices,
            vertices: c.vertex_pool_vertices,
        }),
    }
}

fn status_of(e: PoolError) -> CaveclodStatus {
    match e {
        PoolError::TooSmall { .. } => CaveclodStatus::MemoryTooSmall,
        PoolError::Misaligned => CaveclodStatus::Misaligned,
        _ => CaveclodStatus::InvalidConfig,
    }
}

/// Bytes of the file tables, then bytes in all (the tables, then the words).
fn memory_layout(config: &PoolConfig) -> Result<(usize, usize)> {
    let tables = (config.files as usize)
        .checked_mul(core::mem::size_of::<Table>())
        .and_then(|b| b.checked_next_multiple_of(CAVECLOD_MEMORY_ALIGN))
        .ok_or(CaveclodStatus::InvalidConfig)?;
    let words = Pool::words_needed(config)
        .checked_mul(4)
        .ok_or(CaveclodStatus::InvalidConfig)?;
    Ok((
        tables,
        tables
            .checked_add(words)
            .ok_or(CaveclodStatus::InvalidConfig)?,
    ))
}

/// The pool of an initialised handle.
///
/// # Safety
/// `p` is null or points to a `CaveclodPool` nothing else uses during the call.
pub(crate) unsafe fn pool<'a>(p: *mut CaveclodPool) -> Result<&'a mut Pool> {
    // SAFETY: the caller's contract.
    unsafe { ffi::handle_mut(p, POOL_TAG) }
}

/// The pool of an initialised handle, read only.
///
/// # Safety
/// `p` is null or points to a `CaveclodPool` nothing writes during `'a`.
pub(crate) unsafe fn pool_ref<'a>(p: *const CaveclodPool) -> Result<&'a Pool> {
    // SAFETY: the caller's contract.
    unsafe { ffi::handle(p, POOL_TAG) }
}

/// Writes to `bytes` how much memory (aligned to `CAVECLOD_MEMORY_ALIGN`) a pool of
/// `config` keeps its bookkeeping in; the pool's bytes are apart (`slots * slot_bytes`).
///
/// Thread-safety: any thread, any time.
///
/// # Safety
/// `config` is null or readable; `bytes` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_pool_memory_size(
    config: *const CaveclodPoolConfig,
    bytes: *mut usize,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let config = config_of(unsafe { ffi::input(config) }?);
        let (_, total) = memory_layout(&config)?;
        // SAFETY: the caller's contract.
        unsafe { ffi::output(bytes, total) }
    })
}

/// Makes `out` an empty pool of `config` over `memory[0..memory_bytes]` (at least
/// `caveclod_pool_memory_size`, aligned to `CAVECLOD_MEMORY_ALIGN`, may be uninitialised)
/// and `pool_bytes[0..pool_len]` (`slots * slot_bytes`, aligned to 64). Allocates nothing.
///
/// Returns `CAVECLOD_STATUS_NULL_POINTER`, `CAVECLOD_STATUS_MISALIGNED`,
/// `CAVECLOD_STATUS_MEMORY_TOO_SMALL` or `CAVECLOD_STATUS_INVALID_CONFIG`.
///
/// Thread-safety: any thread; the pool then belongs to one thread at a time.
///
/// # Safety
/// `memory` and `pool_bytes` are null or valid for reads and writes of their lengths, used
/// by nothing else while the pool is in use; `out` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_pool_init(
    config: *const CaveclodPoolConfig,
    memory: *mut core::ffi::c_void,
    memory_bytes: usize,
    pool_bytes: *mut u8,
    pool_len: usize,
    out: *mut CaveclodPool,
) -> CaveclodStatus {
    guarded(|| {
        let out = ffi::checked(out.cast_const())?.cast_mut();
        // SAFETY: `out` is non-null, aligned and writable (the caller's contract).
        unsafe { ffi::clear_tag::<_, Pool>(out) };
        // SAFETY: the caller's contract.
        let config = config_of(unsafe { ffi::input(config) }?);
        let (table_bytes, total) = memory_layout(&config)?;
        if pool_bytes.is_null() {
            return Err(CaveclodStatus::NullPointer);
        }
        let base = ffi::caller_memory(memory, CAVECLOD_MEMORY_ALIGN, memory_bytes, total)?;
        let tables = base.cast::<Table>();
        for i in 0..config.files as usize {
            // SAFETY: `table_bytes` bytes at `base` hold `files` tables, aligned (asserted).
            unsafe { tables.add(i).write(None) };
        }
        // SAFETY: initialised above; used only through this pool while it lives (the
        // caller's contract, which is what `'static` stands for here).
        let tables: &'static mut [Table] =
            unsafe { core::slice::from_raw_parts_mut(tables, config.files as usize) };
        let words_len = Pool::words_needed(&config);
        // SAFETY: `table_bytes + 4 * words_len <= memory_bytes`, the words start on 8 bytes;
        // zeroed before the slice is made, so every `u32` is initialised.
        let words: &'static mut [u32] = unsafe {
            let w = base.add(table_bytes).cast::<u32>();
            w.write_bytes(0, words_len);
            core::slice::from_raw_parts_mut(w, words_len)
        };
        // SAFETY: valid for `pool_len` bytes used only by this pool (the caller's contract).
        let bytes: &'static mut [u8] =
            unsafe { core::slice::from_raw_parts_mut(pool_bytes, pool_len) };
        let residency = Residency::new(config, words, bytes, tables).map_err(status_of)?;
        // SAFETY: `out` is writable and the blob holds a `Cell<Pool>` (asserted).
        unsafe { ffi::fill(out, POOL_TAG, residency) };
        Ok(())
    })
}

/// Adds the paged file whose root is `r` to the pool; writes its file number to `file`.
/// `CAVECLOD_STATUS_INVALID_CONFIG` when the pool is configured for fewer files or pages, or
/// its slots are smaller than the file's largest page.
///
/// # Safety
/// `p` is null or a pool nothing else uses during the call; `r` is null or an opened root
/// that outlives the pool; `file` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_pool_add_file(
    p: *mut CaveclodPool,
    r: *const CaveclodPagedRoot,
    file: *mut u32,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let (p, r) = unsafe { (pool(p)?, paged_root(r)?) };
        let f = p
            .add_file(r.table(), r.paged().root_pages)
            .map_err(status_of)?;
        // SAFETY: the caller's contract.
        unsafe { ffi::output(file, f) }
    })
}

/// Starts a frame: the last frame's requests are forgotten (loads in flight go on).
///
/// # Safety
/// `p` is null or a pool nothing else uses during the call.
#[no_mangle]
pub unsafe extern "C" fn caveclod_pool_begin_frame(p: *mut CaveclodPool) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        unsafe { pool(p) }?.begin_frame();
        Ok(())
    })
}

/// A camera wants page (`file`, `page`) for a split whose screen-space error exceeds the
/// tolerance by `excess` pixels; what the pool found goes to `out`.
/// `CAVECLOD_STATUS_INVALID_ARGUMENT` for a page the pool does not serve.
///
/// # Safety
/// `p` is null or a pool nothing else uses during the call; `out` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_pool_want(
    p: *mut CaveclodPool,
    file: u32,
    page: u32,
    excess: f32,
    out: *mut CaveclodWanted,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let p = unsafe { pool(p) }?;
        let w = p
            .want(PageKey { file, page }, excess)
            .map_err(|_| CaveclodStatus::InvalidArgument)?;
        let w = match w {
            Wanted::Resident => CaveclodWanted::Resident,
            Wanted::Requested => CaveclodWanted::Requested,
            Wanted::Failed => CaveclodWanted::Failed,
            Wanted::Dropped => CaveclodWanted::Dropped,
        };
        // SAFETY: the caller's contract.
        unsafe { ffi::output(out, w) }
    })
}

/// Chooses this frame's loads: writes up to `loads_len` (at most `CAVECLOD_MAX_LOADS`)
/// "load page P into slot S" requests to `loads`, the pages evicted for them (as many at
/// most) to `evicted`, and the counts to `stats`.
///
/// # Safety
/// `p` is null or a pool nothing else uses during the call; `loads` and `evicted` are null
/// (with a zero length) or writable for their lengths; `stats` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_pool_schedule(
    p: *mut CaveclodPool,
    loads: *mut CaveclodLoadRequest,
    loads_len: usize,
    evicted: *mut CaveclodPageKey,
    evicted_len: usize,
    stats: *mut CaveclodScheduleStats,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let (p, out_loads, out_evicted) = unsafe {
            (
                pool(p)?,
                ffi::slice_mut(loads, loads_len)?,
                ffi::slice_mut(evicted, evicted_len)?,
            )
        };
        let mut l = [LoadRequest::default(); CAVECLOD_MAX_LOADS];
        let mut e = [PageKey::default(); CAVECLOD_MAX_LOADS];
        let l_len = out_loads.len().min(CAVECLOD_MAX_LOADS);
        let e_len = out_evicted.len().min(CAVECLOD_MAX_LOADS);
        let l_room = l
            .split_at_mut_checked(l_len)
            .map_or(&mut [][..], |(a, _)| a);
        let e_room = e
            .split_at_mut_checked(e_len)
            .map_or(&mut [][..], |(a, _)| a);
        let s: ScheduleStats = p.schedule(l_room, e_room);
        for (o, r) in out_loads.iter_mut().zip(l.iter().take(s.loads as usize)) {
            *o = CaveclodLoadRequest {
                file: r.key.file,
                page: r.key.page,
                slot: r.slot,
                size: r.size,
                offset: r.offset,
            };
        }
        for (o, k) in out_evicted
            .iter_mut()
            .zip(e.iter().take(s.evictions as usize))
        {
            *o = CaveclodPageKey {
                file: k.file,
                page: k.page,
            };
        }
        let stats_out = CaveclodScheduleStats {
            requested: s.requested,
            loads: s.loads,
            evictions: s.evictions,
            waiting: s.waiting,
            blocked: s.blocked,
            dropped: s.dropped,
        };
        // SAFETY: the caller's contract.
        unsafe { ffi::optional_output(stats, stats_out) }
    })
}

/// Writes the address and length of slot `slot`'s bytes, reserved by a load request, for
/// the host to fill with the page's `size` bytes. `CAVECLOD_STATUS_INVALID_ARGUMENT` when no
/// page is loading into `slot`.
///
/// # Safety
/// `p` is null or a pool nothing else uses during the call; `bytes` and `len` are null or
/// writable. The bytes may be written until `caveclod_pool_install` or `caveclod_pool_fail`.
#[no_mangle]
pub unsafe extern "C" fn caveclod_pool_loading_slot(
    p: *mut CaveclodPool,
    slot: u32,
    bytes: *mut *mut u8,
    len: *mut usize,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let p = unsafe { pool(p) }?;
        let s = p
            .loading_slot_mut(slot)
            .map_err(|_| CaveclodStatus::InvalidArgument)?;
        // SAFETY: the caller's contract.
        unsafe {
            ffi::output(bytes, s.as_mut_ptr())?;
            ffi::output(len, s.len())
        }
    })
}

/// The host filled slot `slot` with the page of the file whose root is `r`: checks it
/// (checksum, then every record against its resident parents) and installs it. A page
/// that fails is written to `fault` (reported once: it stays absent) and the call returns
/// `CAVECLOD_STATUS_BAD_PAGE`; the frame goes on at the coarser level. A page whose parent
/// is still loading returns `CAVECLOD_STATUS_PAGE_WAITS` and keeps its bytes (a frame's
/// loads come parents first, so installing them in that order never waits).
///
/// # Safety
/// `p` is null or a pool nothing else uses during the call; `r` is null or an opened root;
/// `fault` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_pool_install(
    p: *mut CaveclodPool,
    slot: u32,
    r: *const CaveclodPagedRoot,
    fault: *mut CaveclodPageFault,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let (p, r) = unsafe { (pool(p)?, paged_root(r)?) };
        match p.install(slot, r) {
            Ok(_) => Ok(()),
            Err(InstallError::Misuse(_)) => Err(CaveclodStatus::InvalidArgument),
            Err(InstallError::Wait) => Err(CaveclodStatus::PageWaits),
            Err(InstallError::Abandoned(_)) => Err(CaveclodStatus::PageAbandoned),
            Err(InstallError::Fault(f)) => {
                // SAFETY: the caller's contract.
                unsafe { ffi::optional_output(fault, f.into()) }?;
                Err(CaveclodStatus::BadPage)
            }
        }
    })
}

/// The host could not read the page loading into slot `slot`: it fails (written to
/// `fault`, once) and its slot is free again.
///
/// # Safety
/// `p` is null or a pool nothing else uses during the call; `fault` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn caveclod_pool_fail(
    p: *mut CaveclodPool,
    slot: u32,
    fault: *mut CaveclodPageFault,
) -> CaveclodStatus {
    guarded(|| {
        // SAFETY: the caller's contract.
        let p = unsafe { pool(p) }?;
        let f = p.fail(slot).map_err(|_| CaveclodStatus::InvalidArgument)?;
        // SAFETY: the caller's contract.
        unsafe { ffi::optional_output(fault, f.into()) }
    })
}
