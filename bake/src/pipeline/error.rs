//! Why a bake failed: one error for every bake, naming the input.

use crate::hierarchy::BuildError;
use crate::import::ImportError;
use crate::ooc::OocError;
use crate::weld::WeldError;

/// Why a bake failed.
#[derive(Debug, thiserror::Error)]
pub enum BakeError {
    /// Reading the input failed.
    #[error(transparent)]
    Import(#[from] ImportError),
    /// The input has nothing usable.
    #[error("{path}: {source}")]
    Weld {
        /// The input.
        path: String,
        /// Why.
        source: WeldError,
    },
    /// The out-of-core simplification failed.
    #[error(transparent)]
    OutOfCore(#[from] OocError),
    /// The hierarchy build broke an invariant its termination rests on (a baker bug).
    #[error("{path}: {source}")]
    Hierarchy {
        /// The input.
        path: String,
        /// The stage and the invariant.
        source: BuildError,
    },
    /// The baked arrays did not validate (a baker bug).
    #[error("internal error: the baked hierarchy does not validate: {0}")]
    Invalid(caveclod_core::FormatError),
}
