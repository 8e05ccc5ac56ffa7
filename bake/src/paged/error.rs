//! Why a paged file could not be written.

/// Why a paged file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum PagedError {
    /// Reading or writing failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// What failed.
        source: std::io::Error,
    },
    /// The hierarchy is not one the paged form can hold.
    #[error("the hierarchy cannot be paged: {0}")]
    Shape(&'static str),
    /// Page-major ids would not fit 32 bits (or polygon keys would not): larger pages.
    #[error("too many pages for 32-bit ids: choose larger pages")]
    TooLarge,
    /// The written file did not read back (a bug in this writer).
    #[error("{path}: the written file does not read back: {what}")]
    ReadBack {
        /// The file.
        path: String,
        /// What the reader said.
        what: String,
    },
}
