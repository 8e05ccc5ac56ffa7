//! Why a read was refused ([`SubmitError`]) or failed ([`ReadError`]).

use std::io;

/// Why [`PageReader::submit`](super::PageReader::submit) refused a read; nothing was queued.
///
/// [`Full`](Self::Full) and [`NoBuffer`](Self::NoBuffer) pass once reads are handed back
/// (and their buffers dropped); the others are the caller's mistakes and do not.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SubmitError {
    /// [`ReaderConfig::max_in_flight`](super::ReaderConfig::max_in_flight) reads are
    /// submitted and not yet handed back.
    Full {
        /// The limit.
        max_in_flight: usize,
    },
    /// Every buffer is in a read or in a [`PageBuffer`](super::PageBuffer) the caller still
    /// holds.
    NoBuffer {
        /// The number of buffers.
        buffers: usize,
    },
    /// No source has this index.
    UnknownFile {
        /// The index asked for.
        file: u32,
        /// How many sources the reader has.
        files: usize,
    },
    /// The read is longer than a buffer.
    TooLong {
        /// The length asked for.
        len: u32,
        /// [`ReaderConfig::max_read_len`](super::ReaderConfig::max_read_len).
        max_read_len: u32,
    },
}

impl std::fmt::Display for SubmitError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Self::Full { max_in_flight } => {
                write!(f, "{max_in_flight} reads are in flight, the most allowed")
            }
            Self::NoBuffer { buffers } => {
                write!(f, "all {buffers} read buffers are in use")
            }
            Self::UnknownFile { file, files } => {
                write!(f, "file {file} does not exist (the reader has {files})")
            }
            Self::TooLong { len, max_read_len } => {
                write!(
                    f,
                    "a read of {len} bytes is longer than the {max_read_len} allowed"
                )
            }
        }
    }
}

impl std::error::Error for SubmitError {}

/// Why a read failed: which one, and the error from the source (for a range past the end of
/// the source, an [`io::ErrorKind::UnexpectedEof`] error that says so).
#[derive(Debug)]
pub struct ReadError {
    /// The file's index.
    pub file: u32,
    /// Where the read started.
    pub offset: u64,
    /// How many bytes it asked for.
    pub len: u32,
    /// What the source (the operating system, for a file) said.
    pub source: io::Error,
}

impl ReadError {
    /// The error for a read of file `file` whose range ends past the source's `file_len`
    /// bytes.
    pub(super) fn past_end(file: u32, offset: u64, len: u32, file_len: u64) -> Self {
        Self {
            file,
            offset,
            len,
            source: io::Error::new(
                io::ErrorKind::UnexpectedEof,
                format!("the range ends past the end of the file ({file_len} bytes)"),
            ),
        }
    }
}

impl std::fmt::Display for ReadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "file {}: reading {} bytes at offset {}: {}",
            self.file, self.len, self.offset, self.source
        )
    }
}

impl std::error::Error for ReadError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.source)
    }
}
