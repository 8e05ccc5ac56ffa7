//! # caveclod-io
//!
//! Loading `.clod` files on a std platform, in one place for the `caveclod` tool, the
//! viewer, the examples, the benchmarks and the tests:
//!
//! - [`AlignedBytes`] ([`aligned`]): owned bytes on a 64-byte boundary, so no record of the
//!   format straddles two cache lines; buffers of [`HUGE_PAGES_FROM`] bytes or more start on
//!   a huge-page boundary and, on Linux, ask for transparent huge pages.
//! - [`ClodBytes`] ([`mapped`]): a file read through a read-only memory map, served from the
//!   page cache as refinement reads it, or read into [`AlignedBytes`] where it cannot be
//!   mapped.
//! - [`ClodFile`] ([`file`](mod@file)): a file opened by path, whose errors
//!   ([`LoadError`]) name it.
//! - [`PagedFile`] ([`paged_file`]): a paged file, its root read and checked on opening,
//!   its pages left on disk for the page reader.
//! - [`Streamer`] ([`streamer`]): a page pool's loads served by the page reader, one call
//!   a frame: arrived pages installed (checked by their file's root), new loads submitted.
//! - [`CameraPool`] ([`camera_pool`]): many cameras' state memories in one aligned buffer,
//!   one cache line apart, in huge pages where granted.
//! - [`PageReader`] ([`pages`]): the page reader, serving the core's page loads for
//!   streaming: byte-range reads of files on worker threads into a bounded set of reused
//!   buffers, optionally paced by a simulated disk ([`DiskModel`]).
//!
//! caveclod-core's `HierarchyBuf` (its `alloc` feature) is the owned form for engines with
//! an allocator but without std; this crate is for platforms with files and memory maps.
//!
//! ```no_run
//! # fn demo() -> Result<(), Box<dyn std::error::Error>> {
//! use caveclod_core::CameraState;
//! let file = caveclod_io::ClodFile::open("terrain.clod")?;
//! let h = file.hierarchy()?;
//! let mut pool = caveclod_io::CameraPool::new(CameraState::words_needed(&h), 4);
//! for memory in pool.memories() {
//!     let camera = CameraState::new(&h, memory)?;
//!     assert_eq!(camera.active_polygon_count() as usize, h.base_polygon_count());
//! }
//! # Ok(())
//! # }
//! ```
#![deny(missing_docs)]

pub mod aligned;
pub mod camera_pool;
pub mod error;
pub mod file;
pub mod mapped;
pub mod paged_file;
pub mod pages;
pub mod streamer;

pub use aligned::{AlignedBytes, HUGE_PAGES_FROM};
pub use camera_pool::CameraPool;
pub use error::LoadError;
pub use file::ClodFile;
pub use mapped::ClodBytes;
pub use paged_file::PagedFile;
pub use pages::{
    DiskModel, FileSource, PageBuffer, PageReader, PageSource, ReadDone, ReadError, ReadRequest,
    ReaderConfig, ReaderStats, SubmitError,
};
pub use streamer::{FrameStreaming, Streamer};
