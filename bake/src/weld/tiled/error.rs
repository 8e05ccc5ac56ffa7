//! Why a tiled weld failed.

use std::io;

use crate::weld::welded::WeldError;

/// Why a tiled weld failed.
#[derive(Debug, thiserror::Error)]
pub enum TiledWeldError {
    /// The weld itself failed, as the in-core weld would.
    #[error(transparent)]
    Weld(#[from] WeldError),
    /// Reading a tile failed.
    #[error("reading the tiles: {0}")]
    Io(#[from] io::Error),
}
