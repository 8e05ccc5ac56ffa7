//! Writing a `.clod` file one section at a time, never holding the whole file's bytes.
//!
//! The sections are planned from their lengths ([`FilePlan`]), then their bytes pass through
//! a [`SectionWriter`] and a buffered writer into a temporary file beside the target; the
//! header, which carries the checksum of everything after it, is written over the start
//! last. The temporary file replaces the target by a rename only once it is complete, synced
//! and, when asked, read back and validated; on any failure it is removed and the target is
//! left as it was.

use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Read, Seek, SeekFrom, Write};
use std::ops::Range;
use std::path::{Path, PathBuf};

use bytemuck::Pod;
use caveclod_core::format::{
    FilePlan, Pieces, SectionSpec, SectionWriter, Sink, StreamError, WriteError,
};
use caveclod_core::Hierarchy;
use rayon::prelude::*;

use crate::base::atomic::temporary_sibling;
use crate::materials::TextureError;

/// Why writing failed.
#[derive(Debug, thiserror::Error)]
pub enum BakeWriteError {
    /// The arrays do not form a valid hierarchy (a baker bug; nothing was written).
    #[error("internal error, nothing written: {0}")]
    Invalid(#[from] WriteError),
    /// A texture cannot be referred to from the output file (no relative path to it, or
    /// one the format refuses).
    #[error("{path}: {source}")]
    Texture {
        /// The file being written.
        path: PathBuf,
        /// Why.
        source: TextureError,
    },
    /// The file system refused.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

/// Size of the buffer between the section writer and the file.
const BUFFER: usize = 1 << 20;

/// Records [`Sections::put_iter`] gathers before passing them on.
pub const CHUNK_RECORDS: usize = 1 << 16;

/// The buffered temporary file, as a [`Sink`].
struct FileSink(BufWriter<File>);

impl Sink for FileSink {
    type Error = std::io::Error;
    fn put(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.0.write_all(bytes)
    }
}

/// The sections of a file being written, handed to the caller's fill step: each call gives
/// the next bytes of the sections in file order.
pub struct Sections<'s> {
    writer: SectionWriter<'s, FileSink>,
}

impl Sections<'_> {
    /// The next records of the current section.
    pub fn put<T: Pod>(&mut self, records: &[T]) -> Result<(), BakeWriteError> {
        self.writer
            .put(bytemuck::cast_slice(records))
            .map_err(stream_error)
    }

    /// The records of `records`, in order, passed on in chunks of [`CHUNK_RECORDS`]: the
    /// section is written without ever being whole in memory.
    pub fn put_iter<T: Pod>(
        &mut self,
        records: impl IntoIterator<Item = T>,
    ) -> Result<(), BakeWriteError> {
        let mut chunk = Vec::with_capacity(CHUNK_RECORDS);
        for r in records {
            chunk.push(r);
            if chunk.len() == CHUNK_RECORDS {
                self.put(&chunk)?;
                chunk.clear();
            }
        }
        self.put(&chunk)
    }

    /// The records `record(0)`, ..., `record(n - 1)` of the current section, made on all
    /// cores [`CHUNK_RECORDS`] at a time while the chunk before is written: each record
    /// depends on its index alone, so the bytes are those of a loop on one thread. Two
    /// chunks are in memory at once, never the section.
    pub fn put_indexed<T: Pod + Send + Sync>(
        &mut self,
        n: usize,
        record: impl Fn(usize) -> T + Sync + Send,
    ) -> Result<(), BakeWriteError> {
        let make = |chunk: &mut Vec<T>, range: Range<usize>| {
            chunk.clear();
            chunk.par_extend(range.into_par_iter().map(&record));
        };
        let mut ready = Vec::with_capacity(CHUNK_RECORDS.min(n));
        let mut next = Vec::with_capacity(CHUNK_RECORDS.min(n));
        make(&mut ready, 0..CHUNK_RECORDS.min(n));
        let mut at = ready.len();
        loop {
            let end = (at + CHUNK_RECORDS).min(n);
            let (written, ()) = rayon::join(|| self.put(&ready), || make(&mut next, at..end));
            written?;
            if at == end {
                return Ok(());
            }
            std::mem::swap(&mut ready, &mut next);
            at = end;
        }
    }
}

/// What a failed step of the section writer becomes; the caller adds the path to an I/O error.
enum Failure {
    Io(std::io::Error),
    Bake(BakeWriteError),
}

fn stream_error(e: StreamError<std::io::Error>) -> BakeWriteError {
    match e {
        StreamError::Sink(source) => BakeWriteError::Io {
            path: PathBuf::new(),
            source,
        },
        StreamError::Plan(e) => BakeWriteError::Invalid(e),
    }
}

/// What a read-back check hands the validated hierarchy of the written file to, before the
/// rename: a caller's report on the file is then made from the very bytes that were
/// validated, without validating them again.
pub type Inspect<'i> = &'i mut dyn FnMut(&Hierarchy<'_>);

/// Whether the written file is read back and validated before it replaces the target.
pub enum Check<'i> {
    /// The sections were validated before writing ([`caveclod_core::format::validate_parts`]).
    Validated,
    /// Validate the written file ([`Hierarchy::from_bytes`]: checksum, section table, every
    /// record) before the rename, then hand its hierarchy to the [`Inspect`].
    ReadBack(Inspect<'i>),
}

/// Writes the file planned by `specs` at `path`: `fill` gives every section's bytes in
/// order ([`Sections::put`]); then the header goes at the start, the file is synced,
/// validated and inspected if `check` asks, and renamed over `path`. Returns the file's length. On any
/// failure the temporary file is removed and `path` is untouched.
pub fn write_sections(
    path: &Path,
    specs: &[SectionSpec],
    check: Check<'_>,
    fill: impl FnOnce(&mut Sections<'_>) -> Result<(), BakeWriteError>,
) -> Result<u64, BakeWriteError> {
    let plan = FilePlan::new(specs).map_err(BakeWriteError::Invalid)?;
    let tmp = temporary_sibling(path);
    let result = (|| {
        let file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(true)
            .open(&tmp)
            .map_err(Failure::Io)?;
        let sink = FileSink(BufWriter::with_capacity(BUFFER, file));
        let writer = SectionWriter::new(plan, sink).map_err(|e| Failure::Bake(stream_error(e)))?;
        let mut sections = Sections { writer };
        fill(&mut sections).map_err(Failure::Bake)?;
        let (header, FileSink(buffered)) = sections
            .writer
            .finish()
            .map_err(|e| Failure::Bake(stream_error(e)))?;
        let mut file = buffered
            .into_inner()
            .map_err(|e| Failure::Io(e.into_error()))?;
        file.seek(SeekFrom::Start(0)).map_err(Failure::Io)?;
        file.write_all(bytemuck::bytes_of(&header))
            .map_err(Failure::Io)?;
        file.sync_all().map_err(Failure::Io)?;
        if let Check::ReadBack(inspect) = check {
            validate_written(&mut file, inspect)?;
        }
        std::fs::rename(&tmp, path).map_err(Failure::Io)?;
        Ok(plan.file_len())
    })();
    result.map_err(|f| {
        let _ = std::fs::remove_file(&tmp);
        let with_path = |source| BakeWriteError::Io {
            path: path.to_path_buf(),
            source,
        };
        match f {
            Failure::Io(source) => with_path(source),
            Failure::Bake(BakeWriteError::Io { source, .. }) => with_path(source),
            Failure::Bake(e) => e,
        }
    })
}

/// How often the pages of a mapped file read so far are handed back
/// ([`with_pages_released`]).
const RELEASE_EVERY: std::time::Duration = std::time::Duration::from_millis(10);

/// Validates the written file as a reader would, and hands its hierarchy to `inspect`:
/// mapped (page aligned) when the system allows, otherwise read into an aligned buffer.
fn validate_written(file: &mut File, inspect: Inspect<'_>) -> Result<(), Failure> {
    // SAFETY: the map is read-only and shared; the file is this process's own temporary
    // file, which nothing else writes while it is mapped.
    match unsafe { memmap2::Mmap::map(&*file) } {
        Ok(map) => check_released(&map, inspect),
        Err(_) => {
            let len = file.metadata().map_err(Failure::Io)?.len() as usize;
            let mut words = vec![0u64; len.div_ceil(8)];
            let bytes = &mut bytemuck::cast_slice_mut::<u64, u8>(&mut words)[..len];
            file.seek(SeekFrom::Start(0)).map_err(Failure::Io)?;
            file.read_exact(bytes).map_err(Failure::Io)?;
            check(bytes, inspect)
        }
    }
}

/// [`check`] of a mapped file whose pages leave the process as the check and the inspection
/// go ([`with_pages_released`]).
fn check_released(map: &memmap2::Mmap, inspect: Inspect<'_>) -> Result<(), Failure> {
    with_pages_released(map, || check(map, inspect))
}

/// Runs `f`, which reads the mapped file `map`, while a second thread tells the system every
/// few milliseconds (`RELEASE_EVERY`) that the mapping's pages are not needed
/// (`MADV_DONTNEED`). They stay in the page cache, where `f`'s next read of them finds them
/// again, but no longer count in the process's resident memory, so reading a file of any
/// length (validating it, reporting on it) takes the memory its reads touch within one
/// period. The file must not change while mapped, as for any map of it.
pub fn with_pages_released<R>(map: &memmap2::Mmap, f: impl FnOnce() -> R) -> R {
    use std::sync::atomic::{AtomicBool, Ordering};
    let done = AtomicBool::new(false);
    std::thread::scope(|s| {
        let releaser = s.spawn(|| {
            while !done.load(Ordering::Relaxed) {
                std::thread::park_timeout(RELEASE_EVERY);
                // SAFETY: the mapping is a read-only shared map of a file nothing writes
                // while it is mapped, so a page read again after being dropped holds the
                // same bytes: `f` on the other thread reads what it would have read. A
                // failed advice only leaves the pages resident.
                let _ = unsafe { map.unchecked_advise(memmap2::UncheckedAdvice::DontNeed) };
            }
        });
        let result = f();
        done.store(true, Ordering::Relaxed);
        releaser.thread().unpark();
        result
    })
}

/// Validates `bytes` as a reader does (each pass on all cores, [`OnRayon`]), then hands the
/// hierarchy to `inspect`.
fn check(bytes: &[u8], inspect: Inspect<'_>) -> Result<(), Failure> {
    let h = Hierarchy::from_bytes_in(bytes, &OnRayon)
        .map_err(|e| Failure::Bake(BakeWriteError::Invalid(WriteError::Invalid(e))))?;
    inspect(&h);
    Ok(())
}

/// Records a validation piece holds at least: fewer cost more to hand to a thread than they
/// take to check.
const PIECE_RECORDS: usize = 1 << 14;

/// The validation passes of a hierarchy ([`Hierarchy::from_bytes_in`],
/// [`Hierarchy::from_parts_in`]) in pieces on rayon's threads (the pool the caller runs in),
/// a few per thread so that uneven pieces even out. The answer is the one a single piece
/// gives, whatever the threads.
#[derive(Clone, Copy, Debug, Default)]
pub struct OnRayon;

impl Pieces for OnRayon {
    fn fold<T: Send>(
        &self,
        n: usize,
        map: &(dyn Fn(Range<usize>) -> T + Sync),
        join: &dyn Fn(T, T) -> T,
    ) -> T {
        let count = (n / PIECE_RECORDS).clamp(1, 4 * rayon::current_num_threads());
        if count == 1 {
            return map(0..n);
        }
        let answers: Vec<T> = (0..count)
            .into_par_iter()
            .map(|i| map(i * n / count..(i + 1) * n / count))
            .collect();
        let mut answers = answers.into_iter();
        let first = answers.next().unwrap_or_else(|| map(0..0));
        answers.fold(first, join)
    }
}
