//! A `.clod` file named on the command line, mapped and validated for a command.

use std::path::Path;

use caveclod_core::Hierarchy;
use caveclod_io::ClodFile;

/// Maps a .clod file and hands its validated hierarchy, borrowing the mapped bytes, to `f`.
pub fn with_hierarchy<T>(
    path: &Path,
    f: impl FnOnce(&Hierarchy<'_>) -> Result<T, String>,
) -> Result<T, String> {
    // Page aligned: no record straddles two cache lines.
    let file = ClodFile::open(path).map_err(|e| e.to_string())?;
    let h = file.hierarchy().map_err(|e| e.to_string())?;
    f(&h)
}
