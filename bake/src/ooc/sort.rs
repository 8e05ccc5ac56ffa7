//! External merge sort of the soup by spatial key, in memory-bounded chunks, merged on demand.
//!
//! [`RunBuilder`] receives the soup from a reader: it fills a chunk, and when the chunk is full
//! a writer thread sorts it by key and writes it as a sorted run, while the reader fills a
//! second chunk: reading and sorting overlap on two cores. The two chunks together take the
//! memory share the builder is given. A builder of keys alone ([`RunBuilder::keys_only`], what
//! [`super::simplify`] uses: its second pass reads the faces again) sorts the keys in place
//! and writes only them, 8 bytes a triangle. A builder of records ([`RunBuilder::new`]) sorts
//! `(key, index)` pairs and gathers once, so the 96-byte records move once, and writes each
//! run twice: its records, and its keys alone.
//!
//! The runs are never merged into one sorted file of records. [`RunBuilder::finish`] merges
//! only the keys into one sorted key file, counting on the way the distinct octree cells the
//! triangles' centroids fall in at every depth ([`SortedSoup::occupied`]): the number of
//! clusters (and so of output triangles) a clustering level will give, known before
//! clustering. The octree is built over that key file. Records, where the runs have them, are
//! merged as they are consumed: [`SortedSoup::merge_from`] starts a k-way merge of the runs at
//! any position of the sorted order (found by binary searches on the runs' keys), so a
//! consumer can take any range of the octree's leaves straight from the merge without a
//! sorted file of records.
//!
//! The sorted order is by key, then by run, then by position in the run: the same wherever a
//! merge starts. The merges take a run's items in stretches, up to the next best run's head,
//! touching the heap once per stretch: runs of an input read in a spatially coherent order
//! interleave little.

use std::cmp::Reverse;
use std::collections::binary_heap::{BinaryHeap, PeekMut};
use std::fs::File;
use std::io::{self, Write};
use std::os::unix::fs::FileExt;
use std::path::PathBuf;
use std::thread::JoinHandle;

use bytemuck::{Pod, Zeroable};

use super::soup::{Cube, SoupTriangle, KEY_LEVELS, RECORD_BYTES};
use super::stream::SoupSink;
use super::temp::{SpillWriter, TempSpace};
use super::OocError;

/// Bytes of chunk a triangle takes: its item, and twice its `(key, index)` sort pair (the
/// radix sort's scatter buffer) for records, or twice the key (sorted in place) for keys.
const fn chunk_bytes_per_triangle<T: RunItem>() -> usize {
    if T::RECORDS {
        std::mem::size_of::<T>() + 2 * std::mem::size_of::<(u64, u32)>()
    } else {
        2 * std::mem::size_of::<T>()
    }
}

/// What a sort chunk holds per triangle: its whole record ([`SoupTriangle`]) or its key alone
/// (`u64`, for a pass that needs only the order and the occupied cells).
pub trait RunItem: Pod + Default + Send + Sync {
    /// Whether runs of this item have records besides their keys.
    const RECORDS: bool;
    /// The item of a triangle.
    fn of(t: &SoupTriangle) -> Self;
    /// Its spatial key.
    fn key(&self) -> u64;
}

impl RunItem for SoupTriangle {
    const RECORDS: bool = true;
    fn of(t: &SoupTriangle) -> Self {
        *t
    }
    fn key(&self) -> u64 {
        self.key
    }
}

impl RunItem for u64 {
    const RECORDS: bool = false;
    fn of(t: &SoupTriangle) -> Self {
        t.key
    }
    fn key(&self) -> u64 {
        *self
    }
}

/// One sorted run on disk.
#[derive(Clone, Debug)]
pub struct Run {
    /// Its records, sorted by key (`None` for a run of keys alone).
    pub records: Option<PathBuf>,
    /// Its keys alone, in the same order.
    pub keys: PathBuf,
    /// Triangles in it.
    pub count: u64,
}

/// The sorted soup on disk: sorted runs and the merged keys.
pub struct SortedSoup {
    /// The runs, in the order they were written.
    pub runs: Vec<Run>,
    /// Every key in sorted order (`u64` each): the octree's storage.
    pub keys: PathBuf,
    /// Triangles in all.
    pub triangles: u64,
    /// Bounding cube of the keys.
    pub cube: Cube,
    /// Distinct key prefixes (occupied octree cells) at depths `0..=KEY_LEVELS`.
    pub occupied: [u64; KEY_LEVELS as usize + 1],
}

/// What a writer thread gives back: the emptied chunk (for reuse) and its run.
type Written<T> = Result<(Vec<T>, Run), OocError>;

/// Collects the soup into sorted runs: of records ([`RunBuilder::new`]) or of keys alone
/// ([`RunBuilder::keys_only`]).
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

impl<'a> RunBuilder<'a, SoupTriangle> {
    /// A builder of records holding at most `chunk_bytes` of triangles at a time (two chunks
    /// of half that, one filling while the other is sorted and written).
    pub fn new(
        temp: &'a TempSpace,
        chunk_bytes: usize,
        progress: &'a mut dyn FnMut(bool, u64, u64),
    ) -> Self {
        Self::with_chunk_bytes(temp, chunk_bytes, progress)
    }
}

impl<'a> RunBuilder<'a, u64> {
    /// A builder of keys alone (8 bytes a triangle on disk, a twelfth of a record) holding at
    /// most `chunk_bytes` of keys at a time, as [`RunBuilder::new`].
    pub fn keys_only(
        temp: &'a TempSpace,
        chunk_bytes: usize,
        progress: &'a mut dyn FnMut(bool, u64, u64),
    ) -> Self {
        Self::with_chunk_bytes(temp, chunk_bytes, progress)
    }
}

impl<'a, T: RunItem> RunBuilder<'a, T> {
    fn with_chunk_bytes(
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

    /// The cube and triangle count a reader announces.
    fn begin(&mut self, cube: &Cube, triangles_hint: u64) {
        self.cube = Some(*cube);
        self.hint = triangles_hint;
        let cap = self.capacity.min(triangles_hint.max(1024) as usize);
        if self.chunk.capacity() < cap {
            self.chunk.reserve_exact(cap - self.chunk.len());
        }
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
        self.begin(cube, triangles_hint);
        Ok(())
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
        self.keep_pending()?;
        self.begin(cube, triangles_hint);
        Ok(())
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

/// Bits of a radix-sort digit.
const DIGIT_BITS: u32 = 11;

/// Sorts `(key, index)` pairs with increasing indices by key (so by key, then index): a
/// stable least-significant-digit radix sort on 11-bit digits, skipping the digits every key
/// shares (the high digits of a run's keys, which come from one region of the input, mostly
/// are). Six passes at most, linear time, against the `n log n` comparisons of a sort.
fn radix_sort(v: &mut Vec<(u64, u32)>) {
    radix_sort_by(v, |&(k, _)| k);
}

/// The radix sort of [`radix_sort`] on any items by `key` (stable).
fn radix_sort_by<E: Copy + Default>(v: &mut Vec<E>, key: impl Fn(&E) -> u64) {
    let Some(first) = v.first().map(&key) else {
        return;
    };
    const DIGITS: usize = 64usize.div_ceil(DIGIT_BITS as usize);
    const RADIX: usize = 1 << DIGIT_BITS;
    let mask = RADIX as u64 - 1;
    let mut varying = 0u64;
    let mut counts = vec![[0usize; RADIX]; DIGITS];
    for e in v.iter() {
        let k = key(e);
        varying |= k ^ first;
        for (d, c) in counts.iter_mut().enumerate() {
            c[((k >> (d as u32 * DIGIT_BITS)) & mask) as usize] += 1;
        }
    }
    let mut other = vec![E::default(); v.len()];
    for (d, c) in counts.iter_mut().enumerate() {
        let shift = d as u32 * DIGIT_BITS;
        if (varying >> shift) & mask == 0 {
            continue;
        }
        let mut at = 0;
        for n in c.iter_mut() {
            let here = *n;
            *n = at;
            at += here;
        }
        for e in v.iter() {
            let b = ((key(e) >> shift) & mask) as usize;
            other[c[b]] = *e;
            c[b] += 1;
        }
        std::mem::swap(v, &mut other);
    }
}

/// Counts the depths at which `key` starts a new cell after `prev`.
fn count_new_cells(occupied: &mut [u64; KEY_LEVELS as usize + 1], prev: Option<u64>, key: u64) {
    let first = match prev {
        None => 0,
        Some(p) if p == key => return,
        Some(p) => {
            let bit = 63 - (p ^ key).leading_zeros(); // highest differing bit
            (KEY_LEVELS - bit / 3) as usize
        }
    };
    for o in &mut occupied[first..] {
        *o += 1;
    }
}

/// A run's records (or keys) from a position on, read in blocks.
struct Cursor<T: Pod> {
    file: File,
    /// Next record of the file to read into the block.
    next: u64,
    /// One past the last record to read.
    end: u64,
    block: Vec<T>,
    at: usize,
    len: usize,
}

impl<T: Pod> Cursor<T> {
    /// Records `start..end` of `file`, read `block` at a time.
    fn new(file: File, start: u64, end: u64, block: usize) -> io::Result<Self> {
        let block = (block as u64).min(end.saturating_sub(start)).max(1) as usize;
        let mut c = Self {
            file,
            next: start,
            end,
            block: vec![T::zeroed(); block],
            at: 0,
            len: 0,
        };
        c.refill()?;
        Ok(c)
    }

    fn refill(&mut self) -> io::Result<()> {
        let n = (self.end.saturating_sub(self.next)).min(self.block.len() as u64) as usize;
        let size = std::mem::size_of::<T>() as u64;
        self.file.read_exact_at(
            bytemuck::cast_slice_mut(&mut self.block[..n]),
            self.next * size,
        )?;
        self.next += n as u64;
        self.at = 0;
        self.len = n;
        Ok(())
    }

    fn head(&self) -> Option<&T> {
        (self.at < self.len).then(|| &self.block[self.at])
    }

    fn advance(&mut self) -> io::Result<()> {
        self.at += 1;
        if self.at == self.len {
            self.refill()?;
        }
        Ok(())
    }
}

/// A k-way merge of sorted cursors, by key then by cursor.
struct Merge<T: Pod> {
    cursors: Vec<Cursor<T>>,
    heap: BinaryHeap<Reverse<(u64, u32)>>,
    key: fn(&T) -> u64,
}

impl<T: Pod> Merge<T> {
    fn new(cursors: Vec<Cursor<T>>, key: fn(&T) -> u64) -> Self {
        let heap = cursors
            .iter()
            .enumerate()
            .filter_map(|(i, c)| c.head().map(|t| Reverse((key(t), i as u32))))
            .collect();
        Self { cursors, heap, key }
    }

    /// Calls `f` on the next `n` items in order. The leading run gives everything it has
    /// before the next best head in one go, without touching the heap: inputs read in a
    /// spatially coherent order (scans, terrains, exported models) make long stretches.
    fn take(&mut self, n: u64, mut f: impl FnMut(&T)) -> io::Result<()> {
        let mut left = n;
        while left > 0 {
            // The next best head: the smaller child of the heap's root.
            let bound = match self.heap.as_slice() {
                [_, b] => Some(b.0),
                [_, b, c, ..] => Some(b.0.min(c.0)),
                _ => None,
            };
            let Some(mut top) = self.heap.peek_mut() else {
                return Err(io::Error::other("the sorted runs end early"));
            };
            let i = top.0 .1;
            let c = &mut self.cursors[i as usize];
            loop {
                f(&c.block[c.at]);
                left -= 1;
                c.advance()?;
                let Some(t) = c.head() else {
                    PeekMut::pop(top);
                    break;
                };
                let k = (self.key)(t);
                if left == 0 || bound.is_some_and(|b| (k, i) > b) {
                    // Sifts down when `top` drops.
                    top.0 = (k, i);
                    break;
                }
            }
        }
        Ok(())
    }
}

/// Records merged from the sorted runs, from some position of the sorted order on
/// ([`SortedSoup::merge_from`]).
pub struct SoupMerge(Merge<SoupTriangle>);

impl SoupMerge {
    /// Calls `f` on the next `n` triangles in sorted order.
    pub fn take(&mut self, n: u64, f: &mut dyn FnMut(&SoupTriangle)) -> Result<(), OocError> {
        self.0
            .take(n, f)
            .map_err(|e| OocError::temp("reading a sorted run", e))
    }
}

impl SortedSoup {
    /// A merge of the runs' records starting at position `first` of the sorted order, using
    /// about `buffer_bytes` of read buffers.
    pub fn merge_from(&self, first: u64, buffer_bytes: usize) -> Result<SoupMerge, OocError> {
        let rerr = |e| OocError::temp("reading a sorted run", e);
        let open = |p: &PathBuf| File::open(p).map_err(rerr);
        let mut starts = vec![0u64; self.runs.len()];
        if first >= self.triangles {
            for (s, r) in starts.iter_mut().zip(&self.runs) {
                *s = r.count;
            }
        } else if first > 0 {
            // Before `first`: every key below its key, then the equal keys run by run.
            let key = read_key(&open(&self.keys)?, first).map_err(rerr)?;
            let mut need = first;
            let mut equal = Vec::with_capacity(self.runs.len());
            for (s, r) in starts.iter_mut().zip(&self.runs) {
                let f = open(&r.keys)?;
                let lo = lower_bound(&f, r.count, |k| k < key).map_err(rerr)?;
                let hi = lower_bound(&f, r.count, |k| k <= key).map_err(rerr)?;
                *s = lo;
                equal.push(hi - lo);
                need = need.checked_sub(lo).ok_or_else(disagree)?;
            }
            for (s, e) in starts.iter_mut().zip(equal) {
                let t = need.min(e);
                *s += t;
                need -= t;
            }
            if need > 0 {
                return Err(disagree());
            }
        }
        let block = (buffer_bytes / self.runs.len().max(1) / RECORD_BYTES).clamp(16, 1 << 15);
        let cursors = self
            .runs
            .iter()
            .zip(starts)
            .map(|(r, s)| {
                let records = r.records.as_ref().ok_or_else(|| {
                    OocError::temp(
                        "reading a sorted run",
                        io::Error::other("the runs were sorted without their records"),
                    )
                })?;
                Cursor::new(open(records)?, s, r.count, block).map_err(rerr)
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(SoupMerge(Merge::new(cursors, |t: &SoupTriangle| t.key)))
    }
}

fn disagree() -> OocError {
    OocError::temp(
        "reading the sorted runs",
        io::Error::other("the runs disagree with the merged keys"),
    )
}

/// Key `i` of a key file.
fn read_key(f: &File, i: u64) -> io::Result<u64> {
    let mut b = [0u8; 8];
    f.read_exact_at(&mut b, i * 8)?;
    Ok(u64::from_le_bytes(b))
}

/// The first index of a sorted key file of `count` keys whose key fails `before`.
fn lower_bound(f: &File, count: u64, before: impl Fn(u64) -> bool) -> io::Result<u64> {
    let (mut a, mut b) = (0, count);
    while a < b {
        let mid = a + (b - a) / 2;
        if before(read_key(f, mid)?) {
            a = mid + 1;
        } else {
            b = mid;
        }
    }
    Ok(a)
}

/// Merges the runs' keys into one sorted key file, counting occupied cells; returns the file,
/// the number of keys and the counts.
fn merge_keys(
    temp: &TempSpace,
    runs: &[Run],
    merge_bytes: usize,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<(PathBuf, u64, [u64; KEY_LEVELS as usize + 1]), OocError> {
    let total: u64 = runs.iter().map(|r| r.count).sum();
    let rerr = |e| OocError::temp("reading a sorted run", e);
    let werr = |e| OocError::temp("writing the sorted keys", e);
    let block = (merge_bytes / runs.len().max(1) / 8).clamp(512, 1 << 19);
    let cursors = runs
        .iter()
        .map(|r| {
            let f = File::open(&r.keys).map_err(rerr)?;
            Cursor::new(f, 0, r.count, block).map_err(rerr)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut merge = Merge::new(cursors, |k: &u64| *k);
    let mut w = temp.create("sorted-keys", 1 << 20).map_err(werr)?;
    let mut occupied = [0u64; KEY_LEVELS as usize + 1];
    let mut prev = None;
    let mut out: Vec<u64> = Vec::with_capacity(1 << 16);
    let mut done = 0;
    while done < total {
        let n = (total - done).min(1 << 16);
        out.clear();
        merge
            .take(n, |&k| {
                count_new_cells(&mut occupied, prev, k);
                prev = Some(k);
                out.push(k);
            })
            .map_err(rerr)?;
        w.write_all(bytemuck::cast_slice(&out)).map_err(werr)?;
        done += n;
        progress(done, total);
    }
    let path = w.finish().map_err(werr)?;
    Ok((path, total, occupied))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_merge_sorted_from_anywhere_and_cells_are_counted() {
        let temp = TempSpace::new(None, None).unwrap();
        let mut progress = |_, _, _| {};
        // Chunks of 10 triangles: 100 triangles make 10 runs.
        let mut b = RunBuilder::new(
            &temp,
            20 * chunk_bytes_per_triangle::<SoupTriangle>(),
            &mut progress,
        );
        let cube = Cube::around([0.0; 3], [1.0; 3]);
        b.start(&cube, 100).unwrap();
        let mut keys = Vec::new();
        for i in 0..100u64 {
            // Repeated positions (so keys: i % 37), across runs and inside them.
            let j = (i % 37) as f32;
            let position = [(j * 0.618).fract(), (j * 0.37).fract(), j / 37.0];
            let corner = super::super::soup::Corner {
                position,
                // The input position, to check the order among equal keys.
                uv: [i as f32, 0.0],
                ..Default::default()
            };
            let key = cube.key(&[position; 3]);
            keys.push((key, i));
            b.push(&SoupTriangle {
                key,
                corners: [corner; 3],
                ..Default::default()
            })
            .unwrap();
        }
        let sorted = b.finish(1 << 16).unwrap();
        assert_eq!(sorted.runs.len(), 10);
        assert_eq!(sorted.triangles, 100);
        // By key, then by run (runs are consecutive inputs), then by position in the run.
        keys.sort_unstable();
        let bytes = std::fs::read(&sorted.keys).unwrap();
        let got: Vec<u64> = bytes
            .chunks(8)
            .map(bytemuck::pod_read_unaligned::<u64>)
            .collect();
        assert_eq!(got, keys.iter().map(|k| k.0).collect::<Vec<_>>());
        for first in [0, 1, 13, 50, 99, 100] {
            let mut m = sorted.merge_from(first, 1 << 12).unwrap();
            let mut got = Vec::new();
            m.take(100 - first, &mut |t| {
                got.push((t.key, t.corners[0].uv[0] as u64))
            })
            .unwrap();
            assert_eq!(got, keys[first as usize..], "from {first}");
            assert!(m.take(1, &mut |_| {}).is_err());
        }
        // Depth 0: one cell; at full depth, every distinct key.
        assert_eq!(sorted.occupied[0], 1);
        let at = |d: u32| {
            let mut p: Vec<u64> = keys
                .iter()
                .map(|&(k, _)| super::super::soup::key_prefix(k, d))
                .collect();
            p.dedup();
            p.len() as u64
        };
        assert_eq!(sorted.occupied[KEY_LEVELS as usize], at(KEY_LEVELS));
        for d in 0..=KEY_LEVELS {
            assert_eq!(sorted.occupied[d as usize], at(d), "depth {d}");
        }
        // Records and keys of every run, and the merged keys.
        assert_eq!(std::fs::read_dir(temp.path()).unwrap().count(), 21);
    }

    #[test]
    fn a_builder_of_keys_sorts_and_counts_like_one_of_records() {
        let temp = TempSpace::new(None, None).unwrap();
        let cube = Cube::around([0.0; 3], [1.0; 3]);
        let triangles: Vec<SoupTriangle> = (0..100u64)
            .map(|i| {
                let j = (i % 37) as f32;
                let position = [(j * 0.618).fract(), (j * 0.37).fract(), j / 37.0];
                SoupTriangle {
                    key: cube.key(&[position; 3]),
                    ..Default::default()
                }
            })
            .collect();
        let mut p1 = |_, _, _| {};
        let mut records = RunBuilder::new(
            &temp,
            20 * chunk_bytes_per_triangle::<SoupTriangle>(),
            &mut p1,
        );
        let mut p2 = |_, _, _| {};
        let mut keys =
            RunBuilder::keys_only(&temp, 20 * chunk_bytes_per_triangle::<u64>(), &mut p2);
        records.start(&cube, 100).unwrap();
        keys.start(&cube, 100).unwrap();
        for (i, t) in triangles.iter().enumerate() {
            records.push(t).unwrap();
            // Half pushed, half filled in place as the readers do.
            if i % 2 == 0 {
                keys.push(t).unwrap();
            } else {
                *keys.slot().unwrap() = *t;
            }
        }
        let (a, b) = (
            records.finish(1 << 16).unwrap(),
            keys.finish(1 << 16).unwrap(),
        );
        assert_eq!(b.runs.len(), 10);
        assert_eq!(b.triangles, 100);
        assert_eq!(a.occupied, b.occupied);
        assert_eq!(
            std::fs::read(&a.keys).unwrap(),
            std::fs::read(&b.keys).unwrap()
        );
        assert!(b.runs.iter().all(|r| r.records.is_none()));
        let e = b.merge_from(0, 1 << 12).err().unwrap();
        assert!(e.to_string().contains("without their records"), "{e}");
    }

    #[test]
    fn radix_sort_orders_by_key_then_index() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut v: Vec<(u64, u32)> = (0..5000u32)
            .map(|i| {
                state = state
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1);
                // High bits shared, a few distinct values repeated, and the full range.
                let k = match i % 3 {
                    0 => (7 << 50) | (state >> 40),
                    1 => (7 << 50) | (state >> 61),
                    _ => state,
                };
                (k, i)
            })
            .collect();
        let mut want = v.clone();
        want.sort_unstable();
        radix_sort(&mut v);
        assert_eq!(v, want);
        let mut same = vec![(5u64, 0u32), (5, 1), (5, 2)];
        radix_sort(&mut same);
        assert_eq!(same, [(5, 0), (5, 1), (5, 2)]);
        radix_sort(&mut Vec::new());
    }

    #[test]
    fn a_writer_error_comes_back_and_nothing_is_left_writing() {
        let parent = tempfile::tempdir().unwrap();
        let temp = TempSpace::new(Some(parent.path()), Some(50 * RECORD_BYTES as u64)).unwrap();
        let mut progress = |_, _, _| {};
        let mut b = RunBuilder::new(
            &temp,
            20 * chunk_bytes_per_triangle::<SoupTriangle>(),
            &mut progress,
        );
        b.start(&Cube::around([0.0; 3], [1.0; 3]), 0).unwrap();
        let mut result = Ok(());
        for _ in 0..200 {
            result = b.push(&SoupTriangle::default());
            if result.is_err() {
                break;
            }
        }
        let e = result.err().or_else(|| b.finish(1 << 16).err()).unwrap();
        assert!(e.to_string().contains("temporary space full"), "{e}");
        drop(temp);
        assert_eq!(std::fs::read_dir(parent.path()).unwrap().count(), 0);
    }
}
