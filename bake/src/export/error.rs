//! Why an export failed.

use std::path::PathBuf;

/// Why an export failed.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// A texture file has no path from the OBJ's directory.
    #[error("surface {surface} ('{name}'): texture '{texture}': {problem}")]
    Texture {
        /// The surface.
        surface: usize,
        /// Its material's name.
        name: String,
        /// The texture as the `.clod` file names it.
        texture: String,
        /// Why.
        problem: String,
    },
    /// An output would replace a file the export reads.
    #[error("{0}: refusing to write over an input of the export")]
    WouldOverwriteInput(PathBuf),
    /// The file system refused.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}
