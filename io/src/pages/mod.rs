//! The page reader: serves the byte-range reads that the core's streaming asks for, on worker
//! threads, into a bounded set of reused buffers.
//!
//! The core never does I/O. To stream a paged `.clod` file into its fixed pool it asks for
//! "bytes `[offset, offset + len)` of file `file`, for request `tag`" and is later told
//! "here are the bytes" or "that read failed". A [`PageReader`] serves those asks on a std
//! platform: [`PageReader::submit`] queues a [`ReadRequest`] for the worker threads and
//! [`PageReader::poll`] hands back each finished read as a [`ReadDone`] carrying the tag, so
//! the caller matches it to what it asked for. The reader knows files only as
//! [`PageSource`]s (a file, bytes in memory, a host's archive), so it depends on no core type.
//!
//! Memory is bounded: a read's bytes land in one of at most
//! [`max_in_flight`](ReaderConfig::max_in_flight) buffers of
//! [`max_read_len`](ReaderConfig::max_read_len) bytes, each 64-byte aligned
//! ([`AlignedBytes`](crate::AlignedBytes)). A [`PageBuffer`] goes back to the reader's free
//! list when it is dropped, and the queues that carry reads to the threads and back are made
//! large enough for every read in flight up front, so once every buffer exists, reading
//! allocates nothing more ([`ReaderStats::buffers_allocated`] says how many buffers were
//! made); only a failed read's error may allocate.
//!
//! A [`DiskModel`] makes the reader behave like a slower device than the one the bytes come
//! from: each read takes the model's latency plus its length over the model's bandwidth, one
//! read at a time, on the clock the caller passes in. A fly-over driven at a fixed frame rate
//! then sees the same slow disk, frame for frame, on any machine.

mod buffer;
mod disk;
mod error;
mod reader;
mod source;
mod worker;

use std::time::Duration;

pub use buffer::PageBuffer;
pub use disk::DiskModel;
pub use error::{ReadError, SubmitError};
pub use reader::PageReader;
pub use source::{FileSource, PageSource};

/// One read the caller wants: `len` bytes at `offset` of file `file`, known as `tag`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ReadRequest {
    /// The file: an index into the sources given to [`PageReader::new`].
    pub file: u32,
    /// The first byte's position in the file.
    pub offset: u64,
    /// How many bytes (at most [`ReaderConfig::max_read_len`]).
    pub len: u32,
    /// The caller's name for the read, handed back in its [`ReadDone`].
    pub tag: u64,
}

/// A finished read: the bytes, or why there are none.
#[derive(Debug)]
pub struct ReadDone {
    /// The request's tag.
    pub tag: u64,
    /// The request's file.
    pub file: u32,
    /// The bytes asked for (exactly the requested length), or the failure.
    pub result: Result<PageBuffer, ReadError>,
}

/// How a [`PageReader`] works.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReaderConfig {
    /// Worker threads doing the reads (at least one is started).
    pub threads: usize,
    /// Reads submitted and not yet handed back, at most; also the number of buffers (at
    /// least one).
    pub max_in_flight: usize,
    /// The longest read, in bytes: the size of each buffer.
    pub max_read_len: u32,
    /// The simulated device, or `None` to hand reads back as soon as the threads finish them.
    pub disk: Option<DiskModel>,
}

impl Default for ReaderConfig {
    /// Two threads, 32 reads of up to 256 KiB in flight (8 MiB of buffers), no disk model.
    fn default() -> Self {
        Self {
            threads: 2,
            max_in_flight: 32,
            max_read_len: 256 << 10,
            disk: None,
        }
    }
}

/// What a [`PageReader`] has done so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ReaderStats {
    /// Reads handed back with their bytes.
    pub reads: u64,
    /// Bytes handed back.
    pub bytes: u64,
    /// Reads handed back as failed.
    pub failures: u64,
    /// Submissions refused (nothing queued).
    pub refused: u64,
    /// Buffers allocated: at most [`ReaderConfig::max_in_flight`], and no more once each has
    /// been made, however many reads follow.
    pub buffers_allocated: usize,
    /// With a [`DiskModel`], the time reads waited, in total, on the simulated clock for the
    /// device to finish the reads queued before them.
    pub simulated_queue_delay: Duration,
    /// With a [`DiskModel`], the longest such wait of one read.
    pub simulated_max_queue_delay: Duration,
}
