//! The real inputs some tests and benches read: the shared data set that sits beside the
//! repository (`../shared/data` from its root), which a checkout may not have.

use std::path::{Path, PathBuf};

/// The shared data's directory (which may not exist).
pub fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data")
}

/// The file `relative` under the shared data, or `None`, with a note on stderr that the
/// test using it is skipped, when it is absent.
pub fn file(relative: &str) -> Option<PathBuf> {
    let path = dir().join(relative);
    if path.exists() {
        Some(path)
    } else {
        eprintln!("note: {relative} not found under ../shared/data; skipping");
        None
    }
}
