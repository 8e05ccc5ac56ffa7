//! Why an out-of-core simplification, or a streaming reader, failed.

use std::io;

/// Why an out-of-core simplification failed.
#[derive(Debug, thiserror::Error)]
pub enum OocError {
    /// The input could not be read.
    #[error("{file}: {what}: {source}")]
    Io {
        /// The input.
        file: String,
        /// What was being done.
        what: String,
        /// The operating-system error.
        #[source]
        source: io::Error,
    },
    /// The input is malformed or ends early, at a named element.
    #[error("{file}: {at}: {message}")]
    Input {
        /// The input.
        file: String,
        /// The element at fault (`face 12`, `line 7`, `header`).
        at: String,
        /// What is wrong.
        message: String,
    },
    /// The input is valid but not something the streaming readers take.
    #[error("{file}: {message}")]
    Unsupported {
        /// The input.
        file: String,
        /// Why.
        message: String,
    },
    /// The input has no triangles.
    #[error("{file}: no triangles")]
    Empty {
        /// The input.
        file: String,
    },
    /// A temporary file could not be written or read (a full disk, a quota).
    #[error("temporary files: {what}: {source}")]
    Temp {
        /// What was being done.
        what: String,
        /// The operating-system error.
        #[source]
        source: io::Error,
    },
    /// The memory budget cannot hold what one step needs.
    #[error("memory budget of {budget} bytes is too small: {what} needs {needed} bytes (raise --memory-budget{hint})")]
    Budget {
        /// The budget.
        budget: u64,
        /// What does not fit.
        what: String,
        /// Bytes it needs.
        needed: u64,
        /// A further way out, if any.
        hint: &'static str,
    },
}

impl OocError {
    /// [`OocError::Io`]: reading `file` failed while doing `what`.
    pub(crate) fn io(file: &str, what: &str, source: io::Error) -> Self {
        Self::Io {
            file: file.to_string(),
            what: what.to_string(),
            source,
        }
    }

    /// [`OocError::Input`]: `file` is malformed at the element `at`.
    pub(crate) fn input(file: &str, at: &str, message: String) -> Self {
        Self::Input {
            file: file.to_string(),
            at: at.to_string(),
            message,
        }
    }

    /// [`OocError::Temp`]: a temporary file failed while doing `what`.
    pub(crate) fn temp(what: &str, source: io::Error) -> Self {
        Self::Temp {
            what: what.to_string(),
            source,
        }
    }
}
