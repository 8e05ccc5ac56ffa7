//! The clustering pass: the input's faces read a second time and dealt out to clustering
//! threads by octree leaf.
//!
//! The first pass sorts only the triangles' keys ([`super::sort`]): enough for the octree and
//! for the occupied-cell counts that choose the grid resolution, at 8 bytes a triangle of
//! temporary files where whole records would take 96 (writing temporary files, not reading
//! the input, is what a large bake spends its time on). This pass reads the faces again (the
//! vertex records are still in their temporary file) and clusters the triangles as they come.
//!
//! The octree's leaves are shared out in [`PARTS`] contiguous ranges of about equal triangle
//! counts; a triangle belongs to the part whose range its key falls in, and each part has its
//! own [`Clusterer`]. The reader fills blocks of triangles; each thread scans every block for
//! the triangles of its parts. A part's clusterer sees its triangles in input order, and the
//! parts are merged in order, so the clustering is the same whatever the number of threads.

use std::collections::VecDeque;
use std::io;
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::sync::Arc;

use super::cluster::{ClusterOptions, Clusterer};
use super::error::OocError;
use super::octree::Node;
use super::options::{OocOptions, OocStage};
use super::soup::{Cube, SoupTriangle, KEY_LEVELS};
use super::stream::{Input, SoupSink};

/// Parts the leaves are shared into: the most clustering threads, and independent of their
/// number so that the result is too.
pub const PARTS: usize = 8;

/// Triangles in a block handed to the threads.
const BLOCK: usize = 1 << 13;

/// Blocks a thread may have queued.
const QUEUED: usize = 2;

/// Contiguous runs of leaves with about equal triangle counts, `parts` of them (spatially
/// coherent: few clusters on the borders between them); the last ones are empty when there
/// are fewer leaves than parts.
pub fn share_leaves(leaves: &[Node], triangles: u64, parts: usize) -> Vec<&[Node]> {
    let mut out: Vec<&[Node]> = Vec::new();
    let mut rest = leaves;
    for t in 0..parts {
        let want = (triangles - rest.first().map_or(triangles, |l| l.first)) / (parts - t) as u64;
        let mut n = 0;
        let mut sum = 0;
        while n < rest.len() && (sum < want || n == 0) {
            sum += rest[n].count;
            n += 1;
        }
        let (a, b) = rest.split_at(n);
        out.push(a);
        rest = b;
    }
    out
}

/// The clustering of the input at some resolution, over the leaves of the octree.
pub struct Clustering<'a> {
    cube: Cube,
    options: &'a OocOptions,
    /// The lowest key of each part (0 for the first, `u64::MAX` for empty ones).
    starts: [u64; PARTS],
    triangles: u64,
}

impl<'a> Clustering<'a> {
    /// The clustering of `triangles` triangles keyed on `cube`, whose octree has `leaves`.
    pub fn new(cube: Cube, leaves: &[Node], triangles: u64, options: &'a OocOptions) -> Self {
        let mut starts = [u64::MAX; PARTS];
        for (p, part) in share_leaves(leaves, triangles, PARTS).iter().enumerate() {
            if let Some(first) = part.first() {
                starts[p] = first.prefix << (3 * (KEY_LEVELS - first.depth));
            }
        }
        starts[0] = 0;
        Self {
            cube,
            options,
            starts,
            triangles,
        }
    }

    fn new_clusterer(&self, resolution: u32) -> Clusterer {
        Clusterer::new(
            self.cube,
            ClusterOptions {
                weights: self.options.weights,
                ..ClusterOptions::at_resolution(resolution)
            },
        )
    }

    /// The input's faces read once more and clustered at `resolution`, the parts merged.
    pub fn cluster(
        &self,
        input: &mut Input<'_>,
        resolution: u32,
        progress: &mut dyn FnMut(OocStage),
    ) -> Result<Clusterer, OocError> {
        let threads = self.options.threads.clamp(1, PARTS);
        let mut parts: Vec<Clusterer> =
            (0..PARTS).map(|_| self.new_clusterer(resolution)).collect();
        let mut report = |done: u64| {
            progress(OocStage::Cluster(
                resolution,
                done.min(self.triangles),
                self.triangles,
            ))
        };
        let read = if threads == 1 {
            let mut dealer = Dealer::new(Deal::Here(&mut parts, &self.starts), &mut report);
            input
                .faces(&mut dealer)
                .and_then(|r| dealer.end().map(|()| r))
        } else {
            self.cluster_on_threads(input, threads, &mut parts, &mut report)
        }?;
        if read.triangles != self.triangles {
            return Err(OocError::Input {
                file: input.name().to_string(),
                at: "faces".into(),
                message: format!(
                    "the input changed while it was read ({} triangles, then {})",
                    self.triangles, read.triangles
                ),
            });
        }
        let mut parts = parts.into_iter();
        let mut c = parts
            .next()
            .unwrap_or_else(|| self.new_clusterer(resolution));
        let rest: Vec<Clusterer> = parts.collect();
        c.reserve(
            rest.iter().map(Clusterer::cluster_count).sum(),
            rest.iter().map(Clusterer::triangle_count).sum(),
        );
        for p in rest {
            c.merge(&p);
        }
        Ok(c)
    }

    /// The faces read on this thread and clustered on `threads` others, each owning a
    /// contiguous range of the parts.
    fn cluster_on_threads(
        &self,
        input: &mut Input<'_>,
        threads: usize,
        parts: &mut [Clusterer],
        report: &mut dyn FnMut(u64),
    ) -> Result<super::stream::StreamReport, OocError> {
        let starts = &self.starts;
        std::thread::scope(|scope| {
            let mut senders = Vec::with_capacity(threads);
            let mut handles = Vec::with_capacity(threads);
            let mut rest = &mut parts[..];
            let mut first = 0;
            for t in 0..threads {
                let n = PARTS * (t + 1) / threads - PARTS * t / threads;
                let (mine, others) = rest.split_at_mut(n);
                rest = others;
                let (tx, rx) = sync_channel::<Arc<Vec<SoupTriangle>>>(QUEUED);
                senders.push(tx);
                let range = first..first + n;
                first += n;
                handles.push(
                    std::thread::Builder::new()
                        .name("caveclod-cluster".into())
                        .spawn_scoped(scope, move || cluster_blocks(&rx, mine, starts, range))
                        .map_err(|e| OocError::temp("starting a clustering thread", e))?,
                );
            }
            let mut dealer = Dealer::new(Deal::Threads(senders), report);
            let read = input
                .faces(&mut dealer)
                .and_then(|r| dealer.end().map(|()| r));
            // Dropping the senders ends the threads' loops.
            drop(dealer);
            for h in handles {
                if h.join().is_err() {
                    return Err(OocError::temp(
                        "clustering",
                        io::Error::other("a clustering thread panicked"),
                    ));
                }
            }
            read
        })
    }
}

/// The part a key belongs to.
#[inline]
fn part_of(starts: &[u64; PARTS], key: u64) -> usize {
    starts.partition_point(|&s| s <= key).saturating_sub(1)
}

/// A clustering thread: the triangles of the parts `range` (whose clusterers are `parts`)
/// from every block received.
fn cluster_blocks(
    rx: &Receiver<Arc<Vec<SoupTriangle>>>,
    parts: &mut [Clusterer],
    starts: &[u64; PARTS],
    range: std::ops::Range<usize>,
) {
    for block in rx {
        for t in block.iter() {
            let p = part_of(starts, t.key);
            if range.contains(&p) {
                parts[p - range.start].add(t);
            }
        }
    }
}

/// Where full blocks go.
enum Deal<'p> {
    /// Clustered on the reading thread.
    Here(&'p mut [Clusterer], &'p [u64; PARTS]),
    /// Sent to every clustering thread.
    Threads(Vec<SyncSender<Arc<Vec<SoupTriangle>>>>),
}

/// The sink of the clustering pass: fills blocks of triangles and deals them out.
struct Dealer<'p, 'r> {
    deal: Deal<'p>,
    block: Vec<SoupTriangle>,
    /// Blocks sent, oldest first, to be refilled once every thread is done with them.
    sent: VecDeque<Arc<Vec<SoupTriangle>>>,
    done: u64,
    report: &'r mut dyn FnMut(u64),
}

impl<'p, 'r> Dealer<'p, 'r> {
    fn new(deal: Deal<'p>, report: &'r mut dyn FnMut(u64)) -> Self {
        Self {
            deal,
            block: Vec::with_capacity(BLOCK),
            sent: VecDeque::new(),
            done: 0,
            report,
        }
    }

    /// Deals out the filled block and starts an empty one.
    fn deal(&mut self) -> Result<(), OocError> {
        self.done += self.block.len() as u64;
        match &mut self.deal {
            Deal::Here(parts, starts) => {
                for t in &self.block {
                    parts[part_of(starts, t.key)].add(t);
                }
                self.block.clear();
            }
            Deal::Threads(senders) => {
                // A thread has received a block only once it took the one before from its
                // queue, so the oldest of more than `QUEUED + 1` blocks sent is free again.
                let mut next = None;
                if self.sent.len() > QUEUED + 1 {
                    if let Some(Ok(mut b)) = self.sent.pop_front().map(Arc::try_unwrap) {
                        b.clear();
                        next = Some(b);
                    }
                }
                let next = next.unwrap_or_else(|| Vec::with_capacity(BLOCK));
                let block = Arc::new(std::mem::replace(&mut self.block, next));
                for tx in senders.iter() {
                    tx.send(block.clone()).map_err(|_| {
                        OocError::temp(
                            "clustering",
                            io::Error::other("a clustering thread stopped"),
                        )
                    })?;
                }
                self.sent.push_back(block);
            }
        }
        (self.report)(self.done);
        Ok(())
    }

    /// Deals out the last, partly filled block.
    fn end(&mut self) -> Result<(), OocError> {
        if self.block.is_empty() {
            return Ok(());
        }
        self.deal()
    }
}

impl SoupSink for Dealer<'_, '_> {
    fn start(&mut self, _cube: &Cube, _triangles_hint: u64) -> Result<(), OocError> {
        Ok(())
    }

    #[inline]
    fn slot(&mut self) -> Result<&mut SoupTriangle, OocError> {
        if self.block.len() == BLOCK {
            self.deal()?;
        }
        self.block.push(SoupTriangle::default());
        let last = self.block.len() - 1;
        Ok(&mut self.block[last])
    }
}
