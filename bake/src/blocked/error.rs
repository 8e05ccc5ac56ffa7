//! Why a blocked build failed.

use crate::hierarchy::BuildError;

/// Why a blocked build failed.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum BlockedError {
    /// A block's build broke an invariant.
    #[error(transparent)]
    Build(#[from] BuildError),
    /// A block's hierarchy did not fit the whole (a baker bug).
    #[error("internal error: a block's hierarchy does not join the whole: {0}")]
    Stitch(&'static str),
    /// Writing or reading the collapses' temporary file failed.
    #[error("the temporary file of the collapses: {0}")]
    Spill(String),
    /// Writing or reading the welded mesh's temporary files failed.
    #[error("the welded mesh's temporary files: {0}")]
    Store(String),
}
