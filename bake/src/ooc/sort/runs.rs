//! The sorted runs: a [`RunBuilder`] fills a chunk from a reader while a writer thread sorts
//! the previous chunk by key ([`super::radix`]) and writes it as a run, its records (where
//! it has them) and its keys alone.

use std::io::{self, Write};
use std::path::PathBuf;
use std::thread::JoinHandle;

use bytemuck::Zeroable;

use super::merge::merge_keys;
use super::radix::{radix_sort, radix_sort_by};
use super::{Run, RunItem, SortedSoup};
use crate::base::temp::{SpillWriter, TempSpace};
use crate::ooc::error::OocError;
use crate::ooc::soup::{Cube, SoupTriangle};
use crate::ooc::stream::SoupSink;

/// Bytes of chunk a triangle takes: its item, and twice its `(key, index)` sort pair (the
/// radix sort's scatter buffer) for records, or twice the key (sorted in place) for keys.
pub(super) const fn chunk_bytes_per_triangle<T: RunItem>() -> usize {
    if T::RECORDS {
        std::mem::size_of::<T>() + 2 * std::mem::size_of::<(u64, u32)>()
    } else {
        2 * std::mem::size_of::<T>()
    }
}

/// What a writer thread gives back: the emptied chunk (for reuse) and its run.
type Written<T> = Result<(Vec<T>, Run), OocError>;

/// Collects the soup into sorted runs: of records (`T` = [`SoupTriangle`]) or of keys alone
/// (`T` = `u64`); see [`RunBuilder::new`].
pub struct RunBuilder<'a, T: RunItem = SoupTriangle> {
    temp: &'a TempSpace,
    chunk: Vec<T>,
    /// The other chunk, when the writer thread has given it back.
    spare: Vec<T>,
    writer: Option<JoinHandle<Written<T>>>,
    capacity: usize,
    runs: Vec<Run>,
    cube: Option<Cube>,
    total: u64,
    hint: u64,
    progress: &'a mut dyn FnMut(bool, u64, u64),
    /// The triangle a reader is filling in a builder of keys, kept at the next one.
    scratch: SoupTriangle,
    /// Whether `scratch` holds a triangle not yet kept.
    pending: bool,
}

impl<'a, T: RunItem> RunBuilder<'a, T> {
    /// A builder holding at most `chunk_bytes` of items at a time (two chunks of half that,
    /// one filling while the other is sorted and written): of records with
    /// `RunBuilder::<SoupTriangle>::new`, of keys alone (8 bytes a triangle on disk, a
    /// twelfth of a record) with `RunBuilder::<u64>::new`.
    pub fn new(
        temp: &'a TempSpace,
        chunk_bytes: usize,
        progress: &'a mut dyn FnMut(bool, u64, u64),
    ) -> Self {
        let capacity = (chunk_bytes / 2 / chunk_bytes_per_triangle::<T>()).max(1);
        Self {
            temp,
            chunk: Vec::new(),
            spare: Vec::new(),
            writer: None,
            capacity,
            runs: Vec::new(),
            cube: None,
            total: 0,
            hint: 0,
            progress,
            scratch: SoupTriangle::zeroed(),
            pending: false,
        }
    }

    /// Waits for the writer thread, if one is busy, and takes back its chunk and run.
    fn wait(&mut self) -> Result<(), OocError> {
        if let Some(h) = self.writer.take() {
            let (mut chunk, run) = h.join().unwrap_or_else(|_| {
                Err(OocError::temp(
                    "sorting a run",
                    io::Error::other("the sort thread panicked"),
                ))
            })?;
            chunk.clear();
            self.spare = chunk;
            self.runs.push(run);
        }
        Ok(())
    }

    /// Hands the full chunk to a writer thread and goes on with the other one.
    fn flush(&mut self) -> Result<(), OocError> {
        if self.chunk.is_empty() {
            return Ok(());
        }
        self.wait()?;
        let n = self.runs.len();
        let terr = |e| OocError::temp(&format!("writing sorted run {n}"), e);
        // A small buffer: the writer's blocks are larger, and go to the file without a copy.
        let records = if T::RECORDS {
            Some(self.temp.create("run", 1 << 16).map_err(terr)?)
        } else {
            None
        };
        let keys = self.temp.create("run-keys", 1 << 16).map_err(terr)?;
        let chunk = std::mem::replace(&mut self.chunk, std::mem::take(&mut self.spare));
        let count = chunk.len() as u64;
        let h = std::thread::Builder::new()
            .name("caveclod-sort".into())
            .spawn(move || {
                let mut chunk = chunk;
                write_run(&mut chunk, records, keys)
                    .map(|(records, keys)| {
                        let run = Run {
                            records,
                            keys,
                            count,
                        };
                        (chunk, run)
                    })
                    .map_err(|e| OocError::temp(&format!("writing sorted run {n}"), e))
            })
            .map_err(|e| OocError::temp("starting the sort thread", e))?;
        self.writer = Some(h);
        Ok(())
    }

    /// Makes room for one more triangle: grows the chunk up to its capacity (never past it,
    /// as doubling would), or flushes it.
    #[cold]
    fn grow(&mut self) -> Result<(), OocError> {
        let len = self.chunk.len();
        if len >= self.capacity {
            self.flush()?;
        }
        let len = self.chunk.len();
        if len == self.chunk.capacity() {
            let want = (len * 2).max(1024).min(self.capacity);
            self.chunk.reserve_exact(want.max(len + 1) - len);
        }
        Ok(())
    }

    /// Room for one more item in the chunk, counted for the progress.
    #[inline]
    fn room(&mut self) -> Result<(), OocError> {
        if self.chunk.len() == self.chunk.capacity() || self.chunk.len() >= self.capacity {
            self.grow()?;
        }
        self.total += 1;
        if self.total % (1 << 16) == 0 {
            (self.progress)(false, self.total, self.hint.max(self.total));
        }
        Ok(())
    }

    /// Keeps the triangle a reader filled in `scratch`, if any.
    #[inline]
    fn keep_pending(&mut self) -> Result<(), OocError> {
        if self.pending {
            self.pending = false;
            self.room()?;
            self.chunk.push(T::of(&self.scratch));
        }
        Ok(())
    }

    /// The cube and triangle count a reader announces (after keeping the triangle of a
    /// previous reader, if any).
    fn begin(&mut self, cube: &Cube, triangles_hint: u64) -> Result<(), OocError> {
        self.keep_pending()?;
        self.cube = Some(*cube);
        self.hint = triangles_hint;
        let cap = self.capacity.min(triangles_hint.max(1024) as usize);
        if self.chunk.capacity() < cap {
            self.chunk.reserve_exact(cap - self.chunk.len());
        }
        Ok(())
    }

    /// Writes the last run and merges the runs' keys into one sorted key file, using about
    /// `merge_bytes` of buffers. Progress: `(false, read, expected)` while reading,
    /// `(true, merged, total)` while merging.
    pub fn finish(mut self, merge_bytes: usize) -> Result<SortedSoup, OocError> {
        self.keep_pending()?;
        self.flush()?;
        self.wait()?;
        self.chunk = Vec::new();
        self.spare = Vec::new();
        let cube = self.cube.unwrap_or(Cube {
            origin: [0.0; 3],
            size: 1.0,
        });
        let runs = std::mem::take(&mut self.runs);
        let progress = &mut *self.progress;
        let (keys, triangles, occupied) =
            merge_keys(self.temp, &runs, merge_bytes, &mut |d, n| {
                progress(true, d, n)
            })?;
        Ok(SortedSoup {
            runs,
            keys,
            triangles,
            cube,
            occupied,
        })
    }
}

impl<T: RunItem> Drop for RunBuilder<'_, T> {
    /// A builder dropped on an error still waits for its writer, so that nothing writes into
    /// the temporary directory while it is removed.
    fn drop(&mut self) {
        if let Some(h) = self.writer.take() {
            let _ = h.join();
        }
    }
}

impl SoupSink for RunBuilder<'_, SoupTriangle> {
    fn start(&mut self, cube: &Cube, triangles_hint: u64) -> Result<(), OocError> {
        self.begin(cube, triangles_hint)
    }

    /// The record is built in place in the chunk.
    #[inline]
    fn slot(&mut self) -> Result<&mut SoupTriangle, OocError> {
        self.room()?;
        self.chunk.push(SoupTriangle::zeroed());
        let last = self.chunk.len() - 1;
        Ok(&mut self.chunk[last])
    }
}

impl SoupSink for RunBuilder<'_, u64> {
    fn start(&mut self, cube: &Cube, triangles_hint: u64) -> Result<(), OocError> {
        self.begin(cube, triangles_hint)
    }

    fn positions_only(&self) -> bool {
        true
    }

    /// The reader fills a scratch record; its key is kept at the next call (or the finish).
    #[inline]
    fn slot(&mut self) -> Result<&mut SoupTriangle, OocError> {
        self.keep_pending()?;
        self.pending = true;
        Ok(&mut self.scratch)
    }

    fn push(&mut self, t: &SoupTriangle) -> Result<(), OocError> {
        self.keep_pending()?;
        self.room()?;
        self.chunk.push(t.key);
        Ok(())
    }
}

/// Sorts a chunk's triangles by key and writes their records (where there are) and their
/// keys; returns the two paths. Keys alone are sorted in place; records through `(key,
/// index)` pairs and one gather, so the 96-byte records move once.
fn write_run<T: RunItem>(
    chunk: &mut Vec<T>,
    records: Option<SpillWriter>,
    mut keys: SpillWriter,
) -> io::Result<(Option<PathBuf>, PathBuf)> {
    let mut kbuf: Vec<u64> = Vec::with_capacity(4096);
    let Some(mut records) = records else {
        radix_sort_by(chunk, T::key);
        for part in chunk.chunks(4096) {
            kbuf.clear();
            kbuf.extend(part.iter().map(T::key));
            keys.write_all(bytemuck::cast_slice(&kbuf))?;
        }
        return Ok((None, keys.finish()?));
    };
    let mut order: Vec<(u64, u32)> = chunk
        .iter()
        .enumerate()
        .map(|(i, t)| (t.key(), i as u32))
        .collect();
    radix_sort(&mut order);
    let mut buf: Vec<T> = Vec::with_capacity(4096);
    for part in order.chunks(4096) {
        buf.clear();
        buf.extend(part.iter().map(|&(_, i)| chunk[i as usize]));
        records.write_all(bytemuck::cast_slice(&buf))?;
        kbuf.clear();
        kbuf.extend(part.iter().map(|&(k, _)| k));
        keys.write_all(bytemuck::cast_slice(&kbuf))?;
    }
    Ok((Some(records.finish()?), keys.finish()?))
}
