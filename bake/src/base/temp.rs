//! Temporary files: one private directory, removed when the bake ends however it ends, and an
//! optional byte quota.
//!
//! Every temporary file lives in a [`TempSpace`], a fresh directory made inside the chosen
//! parent (`--temp-dir`, or the system's); dropping the space removes the directory with
//! everything in it, so an error anywhere (a truncated input, a full disk) leaves nothing
//! behind, and neither does success. The quota makes "the disk is full" reproducible in tests
//! without mounting anything: writes that would pass it fail with
//! [`std::io::ErrorKind::StorageFull`], exactly as a full disk does.

use std::cell::Cell;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

/// A private temporary directory with a byte quota.
pub struct TempSpace {
    dir: tempfile::TempDir,
    used: Arc<AtomicU64>,
    quota: u64,
    next: Cell<u32>,
}

impl TempSpace {
    /// Makes a fresh directory inside `parent` (the system's temporary directory when `None`).
    pub fn new(parent: Option<&Path>, quota: Option<u64>) -> io::Result<Self> {
        let mut b = tempfile::Builder::new();
        b.prefix("caveclod-ooc-");
        let dir = match parent {
            Some(p) => b.tempdir_in(p)?,
            None => b.tempdir()?,
        };
        Ok(Self {
            dir,
            used: Arc::new(AtomicU64::new(0)),
            quota: quota.unwrap_or(u64::MAX),
            next: Cell::new(0),
        })
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        self.dir.path()
    }

    /// Bytes written so far (files removed early still count).
    pub fn used(&self) -> u64 {
        self.used.load(Ordering::Relaxed)
    }

    /// A new file named after `what` with a sequence number, open for writing through a
    /// buffer of `buffer` bytes.
    pub fn create(&self, what: &str, buffer: usize) -> io::Result<SpillWriter> {
        let n = self.next.get();
        self.next.set(n + 1);
        let path = self.dir.path().join(format!("{n:04}-{what}"));
        let file = File::create(&path)?;
        Ok(SpillWriter {
            inner: BufWriter::with_capacity(buffer.max(4096), file),
            path,
            used: self.used.clone(),
            quota: self.quota,
        })
    }
}

/// A temporary file being written, counted against its space's quota. It may be handed to
/// another thread (the sort writes its runs from one).
pub struct SpillWriter {
    inner: BufWriter<File>,
    path: PathBuf,
    used: Arc<AtomicU64>,
    quota: u64,
}

impl SpillWriter {
    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Flushes and returns the path, for reading back.
    pub fn finish(mut self) -> io::Result<PathBuf> {
        self.inner.flush()?;
        Ok(self.path)
    }
}

impl Write for SpillWriter {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let used = self.used.load(Ordering::Relaxed) + buf.len() as u64;
        if used > self.quota {
            return Err(io::Error::new(
                io::ErrorKind::StorageFull,
                format!("temporary space full (quota of {} bytes)", self.quota),
            ));
        }
        let n = self.inner.write(buf)?;
        self.used.fetch_add(n as u64, Ordering::Relaxed);
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

/// Parses a byte size: a number with an optional `K`, `M`, `G` (powers of 1024) suffix and an
/// optional `B` / `iB` (`256M`, `1.5G`, `300MiB`, `1000000`).
pub fn parse_size(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let t = t
        .strip_suffix("iB")
        .or_else(|| t.strip_suffix('B'))
        .or_else(|| t.strip_suffix('b'))
        .unwrap_or(t);
    let (num, mult) = match t.chars().last() {
        Some('k' | 'K') => (&t[..t.len() - 1], 1u64 << 10),
        Some('m' | 'M') => (&t[..t.len() - 1], 1 << 20),
        Some('g' | 'G') => (&t[..t.len() - 1], 1 << 30),
        Some('t' | 'T') => (&t[..t.len() - 1], 1 << 40),
        _ => (t, 1),
    };
    let v: f64 = num
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a size (expected e.g. 256M, 1.5G, 1000000)"))?;
    if !(v.is_finite() && v >= 0.0) {
        return Err(format!("'{s}' is not a size"));
    }
    Ok((v * mult as f64) as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse() {
        assert_eq!(parse_size("256M").unwrap(), 256 << 20);
        assert_eq!(parse_size("1.5G").unwrap(), 3 << 29);
        assert_eq!(parse_size("300MiB").unwrap(), 300 << 20);
        assert_eq!(parse_size("64kB").unwrap(), 64 << 10);
        assert_eq!(parse_size("1000").unwrap(), 1000);
        assert!(parse_size("lots").is_err());
        assert!(parse_size("-5M").is_err());
    }

    #[test]
    fn quota_fails_like_a_full_disk_and_the_directory_goes() {
        let parent = tempfile::tempdir().unwrap();
        let space = TempSpace::new(Some(parent.path()), Some(100)).unwrap();
        let mut w = space.create("x", 16).unwrap();
        w.write_all(&[0; 60]).unwrap();
        let e = w.write_all(&[0; 60]).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::StorageFull);
        drop(w);
        drop(space);
        assert_eq!(std::fs::read_dir(parent.path()).unwrap().count(), 0);
    }
}
