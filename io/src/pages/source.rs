//! Where a file's bytes come from: [`PageSource`], with a file ([`FileSource`]) and bytes in
//! memory as sources.

use std::fs::File;
use std::io;
use std::path::Path;
use std::sync::Arc;

use crate::aligned::AlignedBytes;
use crate::error::LoadError;
use crate::mapped::ClodBytes;

/// A file's bytes, read at any position from any thread: a file, bytes in memory, or what a
/// host supplies (an archive member, a network cache).
pub trait PageSource: Send + Sync + 'static {
    /// Fills `buf` with the bytes at `offset` (exactly `buf.len()` of them) or fails.
    fn read_at(&self, offset: u64, buf: &mut [u8]) -> io::Result<()>;

    /// The length in bytes, against which each read's range is checked before it is queued.
    fn len(&self) -> u64;

    /// Whether there are no bytes.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A file read with positioned reads, so that threads share it without a common cursor
/// (on other systems than Unix, a cursor under a lock).
///
/// The length is taken when the file is opened: caveclod replaces a `.clod` file by renaming
/// a new one over it and never writes one in place, so an open file keeps its length. A
/// file shortened by another program fails the reads past its new end.
#[derive(Debug)]
pub struct FileSource {
    #[cfg(unix)]
    file: File,
    #[cfg(not(unix))]
    file: std::sync::Mutex<File>,
    len: u64,
}

impl FileSource {
    /// The file at `path`; an error names it.
    pub fn open(path: impl AsRef<Path>) -> Result<Self, LoadError> {
        let path = path.as_ref();
        File::open(path)
            .and_then(Self::new)
            .map_err(|e| LoadError::io(path, e))
    }

    /// An open file.
    pub fn new(file: File) -> io::Result<Self> {
        let len = file.metadata()?.len();
        Ok(Self {
            #[cfg(unix)]
            file,
            #[cfg(not(unix))]
            file: std::sync::Mutex::new(file),
            len,
        })
    }
}

impl PageSource for FileSource {
    #[cfg(unix)]
    fn read_at(&self, offset: u64, buf: &mut [u8]) -> io::Result<()> {
        std::os::unix::fs::FileExt::read_exact_at(&self.file, buf, offset)
    }

    #[cfg(not(unix))]
    fn read_at(&self, offset: u64, buf: &mut [u8]) -> io::Result<()> {
        use std::io::{Read, Seek, SeekFrom};
        let mut file = self
            .file
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        file.seek(SeekFrom::Start(offset))?;
        file.read_exact(buf)
    }

    fn len(&self) -> u64 {
        self.len
    }
}

/// Copies `bytes[offset..offset + buf.len()]` into `buf`, or fails as a short file would.
fn read_slice(bytes: &[u8], offset: u64, buf: &mut [u8]) -> io::Result<()> {
    let range = usize::try_from(offset)
        .ok()
        .and_then(|start| Some(start..start.checked_add(buf.len())?))
        .filter(|r| r.end <= bytes.len());
    match range {
        Some(r) => {
            buf.copy_from_slice(&bytes[r]);
            Ok(())
        }
        None => Err(io::Error::new(
            io::ErrorKind::UnexpectedEof,
            format!(
                "{} bytes at offset {offset} run past the end ({} bytes)",
                buf.len(),
                bytes.len()
            ),
        )),
    }
}

/// Bytes in memory as a source, for tests and for hosts that hold a file whole.
macro_rules! memory_source {
    ($($t:ty),*) => {$(
        impl PageSource for $t {
            fn read_at(&self, offset: u64, buf: &mut [u8]) -> io::Result<()> {
                read_slice(self, offset, buf)
            }

            fn len(&self) -> u64 {
                <[u8]>::len(self) as u64
            }
        }
    )*};
}

memory_source!(
    Vec<u8>,
    Box<[u8]>,
    Arc<[u8]>,
    &'static [u8],
    AlignedBytes,
    ClodBytes
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn memory_reads_inside_the_bytes_and_fails_past_them() {
        let bytes: Vec<u8> = (0..100u8).collect();
        let mut buf = [0u8; 10];
        bytes.read_at(90, &mut buf).unwrap();
        assert_eq!(buf[0], 90);
        assert_eq!(PageSource::len(&bytes), 100);
        let e = bytes.read_at(91, &mut buf).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::UnexpectedEof);
        assert!(e.to_string().contains("offset 91"), "{e}");
        assert!(bytes.read_at(u64::MAX, &mut buf).is_err());
        let empty: &'static [u8] = &[];
        assert!(PageSource::is_empty(&empty));
        empty.read_at(0, &mut []).unwrap();
    }

    #[test]
    fn a_file_reads_at_any_offset_and_fails_past_its_end() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f");
        let src: Vec<u8> = (0..5000u32).map(|i| (i * 7) as u8).collect();
        std::fs::write(&path, &src).unwrap();
        let f = FileSource::open(&path).unwrap();
        assert_eq!(f.len(), 5000);
        let mut buf = vec![0u8; 1000];
        f.read_at(4000, &mut buf).unwrap();
        assert_eq!(buf, src[4000..]);
        f.read_at(17, &mut buf).unwrap();
        assert_eq!(buf, src[17..1017]);
        assert!(f.read_at(4001, &mut buf).is_err());
        let missing = FileSource::open(dir.path().join("missing")).unwrap_err();
        assert!(missing.to_string().contains("missing"), "{missing}");
    }
}
