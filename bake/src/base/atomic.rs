//! Files that appear whole or not at all: written as a temporary sibling, synced, then
//! renamed over the target, so that a reader never sees a partial file and a failure leaves
//! the target as it was.

use std::path::{Path, PathBuf};

/// The temporary file `path` is written as before the rename: a hidden sibling, so the
/// rename stays within one file system.
pub fn temporary_sibling(path: &Path) -> PathBuf {
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    dir.join(format!(".{name}.{}.tmp", std::process::id()))
}

/// Creates a temporary sibling of `path`, lets `fill` write it, syncs it and renames it over
/// `path`: a reader never sees a partial file, and the temporary file is removed on failure.
/// For output streamed as it is made (`write_atomically` for bytes already in memory).
pub fn write_atomically_with(
    path: &Path,
    fill: impl FnOnce(&mut std::fs::File) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let tmp = temporary_sibling(path);
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        fill(&mut f)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}
