//! `.clod` files read through a memory map: the kernel pages the file in as refinement reads
//! it, so a hierarchy larger than the memory a process should hold on its heap is served from
//! the page cache, and the core borrows the mapped bytes as it borrows any others.
//!
//! A mapping starts on a page boundary, so the sections (each on a multiple of 64 bytes from
//! the file's start) sit on cache lines as they do in [`AlignedBytes`]. The bytes must not
//! change while mapped: caveclod writes every `.clod` to a temporary file renamed over the
//! old one, which leaves a mapped file's bytes as they were. Where a file cannot be mapped
//! (an empty one, a file system without mappings), it is read into [`AlignedBytes`].

use std::fs::File;
use std::path::Path;

use caveclod_core::{FormatError, Hierarchy};

use crate::aligned::AlignedBytes;
use crate::error::LoadError;

/// The bytes of a `.clod` file: mapped, or read into aligned memory.
pub enum ClodBytes {
    /// A read-only memory map of the whole file.
    Mapped(memmap2::Mmap),
    /// Bytes in the heap (a file that cannot be mapped, or a bake made in memory).
    Owned(AlignedBytes),
}

impl std::fmt::Debug for ClodBytes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Mapped(m) => write!(f, "ClodBytes::Mapped({} bytes)", m.len()),
            Self::Owned(b) => write!(f, "ClodBytes::Owned({} bytes)", b.len()),
        }
    }
}

impl ClodBytes {
    /// The file at `path`, mapped where the system allows, else read.
    pub fn open(path: &Path) -> Result<Self, LoadError> {
        let io = |e| LoadError::io(path, e);
        let file = File::open(path).map_err(io)?;
        if file.metadata().map_err(io)?.len() == 0 {
            return Ok(Self::Owned(AlignedBytes::zeroed(0)));
        }
        // SAFETY: the map is read-only and private to this process; its bytes stay valid as
        // long as nobody writes the file in place while it is mapped, which caveclod never
        // does (its writers rename a finished temporary file over the old one). A file
        // truncated by another program under the map is outside what this reader supports,
        // as it is for every memory-mapped reader.
        match unsafe { memmap2::Mmap::map(&file) } {
            Ok(map) => Ok(Self::Mapped(map)),
            Err(_) => AlignedBytes::read(path).map(Self::Owned),
        }
    }

    /// The bytes.
    pub fn bytes(&self) -> &[u8] {
        match self {
            Self::Mapped(m) => m,
            Self::Owned(b) => b.bytes(),
        }
    }

    /// Whether the bytes are a memory map.
    pub fn is_mapped(&self) -> bool {
        matches!(self, Self::Mapped(_))
    }

    /// The hierarchy in the bytes (validated on each call).
    pub fn hierarchy(&self) -> Result<Hierarchy<'_>, FormatError> {
        Hierarchy::from_bytes(self.bytes())
    }
}

impl From<AlignedBytes> for ClodBytes {
    fn from(b: AlignedBytes) -> Self {
        Self::Owned(b)
    }
}

impl std::ops::Deref for ClodBytes {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        self.bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mapped_file_holds_the_bytes_of_a_read_one_on_a_page_boundary() {
        let dir = tempfile::tempdir().unwrap();
        for len in [1usize, 63, 4096, 100_000] {
            let path = dir.path().join(format!("f{len}"));
            let src: Vec<u8> = (0..len).map(|i| (i * 13 + 5) as u8).collect();
            std::fs::write(&path, &src).unwrap();
            let mapped = ClodBytes::open(&path).unwrap();
            assert!(mapped.is_mapped(), "len {len}");
            assert_eq!(mapped.bytes(), &src[..]);
            assert_eq!(mapped.as_ptr() as usize % 4096, 0);
        }
        let empty = dir.path().join("empty");
        std::fs::write(&empty, []).unwrap();
        let e = ClodBytes::open(&empty).unwrap();
        assert!(!e.is_mapped());
        assert!(e.is_empty());
        assert!(e.hierarchy().is_err());
        let missing = dir.path().join("missing");
        let e = ClodBytes::open(&missing).unwrap_err();
        assert_eq!(e.path(), missing);
    }
}
