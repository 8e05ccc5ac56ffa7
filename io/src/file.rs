//! A `.clod` file opened by path: its bytes (mapped where the system allows) and its
//! hierarchy, with every error naming the file.

use std::path::{Path, PathBuf};

use caveclod_core::Hierarchy;

use crate::error::LoadError;
use crate::mapped::ClodBytes;

/// A `.clod` file's bytes and where they came from, so that what goes wrong names the file.
///
/// ```no_run
/// # fn demo() -> Result<(), caveclod_io::LoadError> {
/// let file = caveclod_io::ClodFile::open("terrain.clod")?;
/// let h = file.hierarchy()?;
/// println!("{}: {} nodes", file.path().display(), h.nodes().len());
/// # Ok(())
/// # }
/// ```
#[derive(Debug)]
pub struct ClodFile {
    path: PathBuf,
    bytes: ClodBytes,
}

impl ClodFile {
    /// The file at `path`, mapped where the system allows, else read ([`ClodBytes::open`]).
    pub fn open(path: impl AsRef<Path>) -> Result<Self, LoadError> {
        let path = path.as_ref();
        Ok(Self {
            bytes: ClodBytes::open(path)?,
            path: path.to_path_buf(),
        })
    }

    /// Where the bytes came from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The bytes.
    pub fn bytes(&self) -> &ClodBytes {
        &self.bytes
    }

    /// The bytes, for an owner that outlives this value's path.
    pub fn into_bytes(self) -> ClodBytes {
        self.bytes
    }

    /// The hierarchy in the bytes (validated on each call); an invalid file's error names it.
    pub fn hierarchy(&self) -> Result<Hierarchy<'_>, LoadError> {
        self.bytes
            .hierarchy()
            .map_err(|e| LoadError::format(&self.path, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_name_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("not_a.clod");
        std::fs::write(&path, [7u8; 200]).unwrap();
        let file = ClodFile::open(&path).unwrap();
        assert_eq!(file.path(), path);
        assert_eq!(file.bytes().len(), 200);
        let e = file.hierarchy().unwrap_err();
        assert!(matches!(e, LoadError::Format { .. }), "{e:?}");
        assert!(
            e.to_string().starts_with(&path.display().to_string()),
            "{e}"
        );
        let missing = ClodFile::open(dir.path().join("missing.clod")).unwrap_err();
        assert!(matches!(missing, LoadError::Io { .. }), "{missing:?}");
        assert!(missing.to_string().contains("missing.clod"), "{missing}");
    }
}
