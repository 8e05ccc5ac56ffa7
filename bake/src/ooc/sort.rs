//! External merge sort of the soup by spatial key, in memory-bounded chunks.
//!
//! [`RunBuilder`] receives the soup from a reader: it fills a chunk as large as its share of
//! the memory budget, sorts it by key (a sort of `(key, index)` pairs, then one gather into
//! the output buffer, so the 96-byte records move once) and writes it as a sorted run. [`merge`]
//! merges the runs with a heap into one sorted file, reading each run through a buffer of an
//! equal share of the budget. An input that fits one chunk is written sorted straight away.
//!
//! While merging, the sort counts the distinct octree cells the triangles' centroids fall in
//! at every depth ([`SortedSoup::occupied`]): the number of clusters (and so of output
//! triangles) a clustering level will give, known before clustering.

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::fs::File;
use std::io::{BufReader, Read, Write};
use std::path::PathBuf;

use super::soup::{Cube, SoupTriangle, KEY_LEVELS, RECORD_BYTES};
use super::stream::SoupSink;
use super::temp::TempSpace;
use super::OocError;

/// The sorted soup on disk.
pub struct SortedSoup {
    /// The sorted file.
    pub path: PathBuf,
    /// Triangles in it.
    pub triangles: u64,
    /// Bounding cube of the keys.
    pub cube: Cube,
    /// Distinct key prefixes (occupied octree cells) at depths `0..=KEY_LEVELS`.
    pub occupied: [u64; KEY_LEVELS as usize + 1],
    /// Sorted runs written before merging.
    pub runs: usize,
}

/// Collects the soup into sorted runs.
pub struct RunBuilder<'a> {
    temp: &'a TempSpace,
    chunk: Vec<SoupTriangle>,
    capacity: usize,
    runs: Vec<(PathBuf, u64)>,
    cube: Option<Cube>,
    total: u64,
    hint: u64,
    progress: &'a mut dyn FnMut(bool, u64, u64),
}

impl<'a> RunBuilder<'a> {
    /// A builder holding at most `chunk_bytes` of triangles at a time.
    pub fn new(
        temp: &'a TempSpace,
        chunk_bytes: usize,
        progress: &'a mut dyn FnMut(bool, u64, u64),
    ) -> Self {
        let capacity = (chunk_bytes / (RECORD_BYTES + 12)).max(1);
        Self {
            temp,
            chunk: Vec::new(),
            capacity,
            runs: Vec::new(),
            cube: None,
            total: 0,
            hint: 0,
            progress,
        }
    }

    fn flush(&mut self) -> Result<(), OocError> {
        if self.chunk.is_empty() {
            return Ok(());
        }
        let mut order: Vec<(u64, u32)> = self
            .chunk
            .iter()
            .enumerate()
            .map(|(i, t)| (t.key, i as u32))
            .collect();
        order.sort_unstable();
        let what = format!("run {}", self.runs.len());
        let terr = |e| OocError::temp(&format!("writing sorted {what}"), e);
        let mut w = self.temp.create("run", 1 << 20).map_err(terr)?;
        let mut buf: Vec<SoupTriangle> = Vec::with_capacity(4096);
        for part in order.chunks(4096) {
            buf.clear();
            buf.extend(part.iter().map(|&(_, i)| self.chunk[i as usize]));
            w.write_all(bytemuck::cast_slice(&buf)).map_err(terr)?;
        }
        let path = w.finish().map_err(terr)?;
        self.runs.push((path, self.chunk.len() as u64));
        self.chunk.clear();
        Ok(())
    }

    /// Writes the last run and merges all runs into one sorted file, using about
    /// `merge_bytes` of buffers. Progress: `(false, read, expected)` while reading,
    /// `(true, merged, total)` while merging.
    pub fn finish(mut self, merge_bytes: usize) -> Result<SortedSoup, OocError> {
        self.flush()?;
        self.chunk = Vec::new();
        let cube = self.cube.unwrap_or(Cube {
            origin: [0.0; 3],
            size: 1.0,
        });
        let progress = self.progress;
        merge(self.temp, self.runs, cube, merge_bytes, &mut |d, n| {
            progress(true, d, n)
        })
    }
}

impl SoupSink for RunBuilder<'_> {
    fn start(&mut self, cube: &Cube, triangles_hint: u64) -> Result<(), OocError> {
        self.cube = Some(*cube);
        self.hint = triangles_hint;
        let cap = self.capacity.min(triangles_hint.max(1024) as usize);
        self.chunk = Vec::with_capacity(cap);
        Ok(())
    }

    fn push(&mut self, t: &SoupTriangle) -> Result<(), OocError> {
        if self.chunk.len() >= self.capacity {
            self.flush()?;
        }
        self.chunk.push(*t);
        self.total += 1;
        if self.total % (1 << 16) == 0 {
            (self.progress)(false, self.total, self.hint.max(self.total));
        }
        Ok(())
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

/// Merges sorted runs into one sorted file.
fn merge(
    temp: &TempSpace,
    runs: Vec<(PathBuf, u64)>,
    cube: Cube,
    merge_bytes: usize,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<SortedSoup, OocError> {
    let total: u64 = runs.iter().map(|r| r.1).sum();
    let mut occupied = [0u64; KEY_LEVELS as usize + 1];
    let rerr = |e| OocError::temp("reading a sorted run", e);
    let n_runs = runs.len();
    if n_runs == 1 {
        // Already sorted: count the cells in one read.
        let (path, count) = runs.into_iter().next().unwrap_or_default();
        let mut r = BufReader::with_capacity(1 << 20, File::open(&path).map_err(rerr)?);
        let mut prev = None;
        let mut t = SoupTriangle::default();
        for i in 0..count {
            r.read_exact(bytemuck::bytes_of_mut(&mut t)).map_err(rerr)?;
            count_new_cells(&mut occupied, prev, t.key);
            prev = Some(t.key);
            if i % (1 << 16) == 0 {
                progress(i, count);
            }
        }
        return Ok(SortedSoup {
            path,
            triangles: count,
            cube,
            occupied,
            runs: 1,
        });
    }
    let buffer = (merge_bytes / n_runs.max(1)).clamp(RECORD_BYTES * 16, 1 << 22);
    let mut readers = Vec::with_capacity(n_runs);
    let mut left = Vec::with_capacity(n_runs);
    let mut heap = BinaryHeap::with_capacity(n_runs);
    let mut heads = vec![SoupTriangle::default(); n_runs];
    for (i, (path, count)) in runs.iter().enumerate() {
        let mut r = BufReader::with_capacity(buffer, File::open(path).map_err(rerr)?);
        if *count > 0 {
            r.read_exact(bytemuck::bytes_of_mut(&mut heads[i]))
                .map_err(rerr)?;
            heap.push(Reverse((heads[i].key, i)));
        }
        readers.push(r);
        left.push(count.saturating_sub(1));
    }
    let werr = |e| OocError::temp("writing the sorted soup", e);
    let mut w = temp.create("sorted", buffer.max(1 << 20)).map_err(werr)?;
    let mut prev = None;
    let mut done = 0u64;
    while let Some(Reverse((key, i))) = heap.pop() {
        w.write_all(bytemuck::bytes_of(&heads[i])).map_err(werr)?;
        count_new_cells(&mut occupied, prev, key);
        prev = Some(key);
        done += 1;
        if done % (1 << 16) == 0 {
            progress(done, total);
        }
        if left[i] > 0 {
            left[i] -= 1;
            readers[i]
                .read_exact(bytemuck::bytes_of_mut(&mut heads[i]))
                .map_err(rerr)?;
            heap.push(Reverse((heads[i].key, i)));
        }
    }
    drop(readers);
    for (path, _) in &runs {
        let _ = std::fs::remove_file(path);
    }
    let path = w.finish().map_err(werr)?;
    Ok(SortedSoup {
        path,
        triangles: total,
        cube,
        occupied,
        runs: n_runs,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_merge_sorted_and_cells_are_counted() {
        let temp = TempSpace::new(None, None).unwrap();
        let mut progress = |_, _, _| {};
        // Chunks of 10 triangles: 100 triangles make 10 runs.
        let mut b = RunBuilder::new(&temp, 10 * (RECORD_BYTES + 12), &mut progress);
        let cube = Cube::around([0.0; 3], [1.0; 3]);
        b.start(&cube, 100).unwrap();
        let mut keys = Vec::new();
        for i in 0..100u64 {
            let key = (((i * 7919) % 97) << 40) | i;
            keys.push(key);
            b.push(&SoupTriangle {
                key,
                ..Default::default()
            })
            .unwrap();
        }
        let sorted = b.finish(1 << 16).unwrap();
        assert_eq!(sorted.runs, 10);
        assert_eq!(sorted.triangles, 100);
        let bytes = std::fs::read(&sorted.path).unwrap();
        let got: Vec<u64> = bytes
            .chunks(RECORD_BYTES)
            .map(|c| bytemuck::pod_read_unaligned::<SoupTriangle>(c).key)
            .collect();
        keys.sort_unstable();
        assert_eq!(got, keys);
        // Depth 0: one cell; at full depth, every distinct key.
        assert_eq!(sorted.occupied[0], 1);
        assert_eq!(sorted.occupied[KEY_LEVELS as usize], 100);
        let at = |d: u32| {
            let mut p: Vec<u64> = keys
                .iter()
                .map(|&k| super::super::soup::key_prefix(k, d))
                .collect();
            p.dedup();
            p.len() as u64
        };
        for d in 0..=KEY_LEVELS {
            assert_eq!(sorted.occupied[d as usize], at(d), "depth {d}");
        }
        // Only the sorted file is left.
        assert_eq!(std::fs::read_dir(temp.path()).unwrap().count(), 1);
    }
}
