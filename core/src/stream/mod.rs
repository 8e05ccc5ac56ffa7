//! Streaming: the pages of paged files in a pool of a fixed size that the caller grants.
//!
//! A paged `.clod` keeps a small root always resident (the base mesh, the top of the
//! hierarchy, and a [`PageTable`]) and groups the rest into pages, each a connected fragment
//! of the vertex hierarchy with the records, vertices and polygons its splits create. A
//! [`Residency`] tracks, for any number of files at once (pages are keyed by
//! [`PageKey`]: file and page), which pages are in the pool, and turns what the cameras
//! want into loads for the host:
//!
//! 1. [`Residency::begin_frame`]; cameras refine over a [`StreamedHierarchy`] (the root and
//!    the resident pages). A split that needs an absent page is deferred, the camera shows
//!    the coarser surface, and the page is listed with the split's screen-space error
//!    excess; the host hands the list to [`Residency::want`].
//! 2. [`Residency::schedule`] adds the absent parents those pages need, picks the loadable
//!    ones (every parent resident) in order of the largest excess, and gives each a free
//!    slot or the slot of the least recently wanted page that no camera's front uses and no
//!    resident page hangs from: "load page P into slot S".
//! 3. The host reads the bytes (on its threads, from a file, an archive or the network)
//!    into [`Residency::loading_slot_mut`] and calls [`Residency::complete`], which checks
//!    the page's checksum and contents, or [`Residency::fail`]. A bad page is reported
//!    there, once, and stays absent; the frame goes on at the coarser level.
//! 4. When the pool is nearly full or the reads fall behind, a [`Pressure`] scales every
//!    camera's tolerance up (and back down when they catch up).
//!
//! Closure holds throughout: a page is resident only while its parents are, so a collapse
//! never needs I/O and eviction goes from the leaves up. The pool's bookkeeping and bytes
//! are caller memory sized by a [`PoolConfig`]; nothing allocates, and no call's work grows
//! with the files' sizes: requests, parents and the eviction list are touched, never scanned.

mod arrays;
mod config;
mod fault;
mod frame_lists;
mod hierarchy;
mod install;
mod lists;
mod pressure;
mod requests;
mod residency;
mod vertex_pool;

pub use crate::format::paged::{PageEntry, PageField, PageTable, PageTableError};
pub use crate::ids::PageKey;
pub use config::{FileTables, PoolConfig, PoolError, VertexPoolLayout};
pub use fault::{FaultKind, InstallError, PageFault, StreamError};
pub use frame_lists::{FrameLists, StreamedReads, Want};
pub use hierarchy::StreamedHierarchy;
pub use pressure::{Pressure, PressureSignal};
pub use residency::{LoadRequest, PageState, PoolStats, Residency, ScheduleStats, Wanted};
pub use vertex_pool::VertexInstall;
