//! Per-camera cuts of the octree: selection against a [`View`] and per-surface index
//! emission.
//!
//! A cut lives in caller memory, [`OctreeCut::words_needed`] words: a per-surface index count
//! and two halves of `node_count` words, one holding the current cut (node ids, ascending) and
//! one the previous, so the nodes that entered and left the cut are known after each
//! selection. Selection is a breadth-first walk whose queue lives in the half being written:
//! every node is queued at most once (it has one parent), and a taken node is written at or
//! before the queue entry just read, so `node_count` words hold queue and cut together and no
//! stack is needed however deep the tree. Because node ids are breadth first, the cut comes out
//! ascending, and comparing it with the previous one is a merge.

use glam::Vec3;

use super::model::{Octree, OctreeNode};
use crate::ids::SurfaceId;
use crate::outputs::{check_lists, start_packed};
use crate::params::ParamsError;
use crate::screen::ScreenTest;
use crate::view::View;

/// Why a cut could not be made, selected or emitted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CutError {
    /// The memory given is too small ([`OctreeCut::words_needed`]).
    Capacity {
        /// Words needed.
        needed: usize,
        /// Words given.
        given: usize,
    },
    /// The cut was made for another octree.
    WrongOctree,
    /// Fewer output lists (or offsets) than the octree has surfaces (plus one).
    TooFewOutputs {
        /// Needed.
        needed: usize,
        /// Given.
        given: usize,
    },
    /// An output list is too short.
    OutputTooSmall {
        /// The surface; `None` for the packed output of all surfaces.
        surface: Option<SurfaceId>,
        /// Indices needed.
        needed: usize,
        /// Room given.
        given: usize,
    },
    /// The tolerance is not a finite number of pixels above 0 (the rule of
    /// [`RefineParams::tolerance_px`](crate::RefineParams::tolerance_px)): nothing was
    /// selected.
    InvalidParams(ParamsError),
}

crate::outputs::from_shortfall!(CutError);

impl From<ParamsError> for CutError {
    fn from(e: ParamsError) -> Self {
        Self::InvalidParams(e)
    }
}

impl core::fmt::Display for CutError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::Capacity { needed, given } => {
                write!(f, "octree cut memory: {given} words given, {needed} needed")
            }
            Self::WrongOctree => write!(f, "octree cut belongs to another octree"),
            Self::TooFewOutputs { needed, given } => {
                write!(f, "{given} index outputs given, {needed} needed")
            }
            Self::OutputTooSmall {
                surface,
                needed,
                given,
            } => crate::outputs::write_too_small(f, surface, needed, given),
            Self::InvalidParams(e) => write!(f, "octree selection refused: {e}"),
        }
    }
}

impl core::error::Error for CutError {}

/// What one selection did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SelectStats {
    /// Nodes in the cut.
    pub selected: u32,
    /// Triangles of the cut, all surfaces.
    pub triangles: u32,
    /// Nodes in the cut that were not in the previous one (their data is needed now).
    pub entered: u32,
    /// Nodes of the previous cut that are not in this one (their data may go).
    pub left: u32,
    /// Nodes skipped, with their subtrees, because their box is outside the frustum.
    pub culled: u32,
    /// Nodes looked at.
    pub visited: u32,
}

/// One camera's cut of an [`Octree`], in caller memory.
#[derive(Debug)]
pub struct OctreeCut<'m> {
    identity: u64,
    node_count: u32,
    /// Which half holds the current cut.
    current: usize,
    /// Length of the cut in each half.
    len: [u32; 2],
    /// Indices per surface in the current cut.
    counts: &'m mut [u32],
    /// Two halves of `node_count` words.
    halves: &'m mut [u32],
}

/// Is any part of the box inside every plane? (The box's extent along each plane normal
/// against the plane: exact for a box, tighter than its bounding sphere.)
#[inline]
fn box_visible(view: &View, node: &OctreeNode) -> bool {
    let (lo, hi) = (Vec3::from_array(node.min), Vec3::from_array(node.max));
    let (c, e) = ((lo + hi) * 0.5, (hi - lo) * 0.5);
    let n = (view.plane_count as usize).min(view.planes.len());
    view.planes[..n].iter().all(|p| {
        let normal = p.truncate();
        normal.dot(c) + normal.abs().dot(e) + p.w >= 0.0
    })
}

/// Distance from `eye` to the node's box (0 inside).
#[inline]
fn box_distance(eye: Vec3, node: &OctreeNode) -> f32 {
    let q = eye
        .max(Vec3::from_array(node.min))
        .min(Vec3::from_array(node.max));
    (eye - q).length()
}

impl<'m> OctreeCut<'m> {
    /// Words of memory a cut of `o` needs: one per surface and two per node.
    pub fn words_needed(o: &Octree<'_>) -> usize {
        o.surface_count() + 2 * o.node_count()
    }

    /// An empty cut of `o` in `memory` (its first [`words_needed`](Self::words_needed)
    /// words).
    pub fn new(o: &Octree<'_>, memory: &'m mut [u32]) -> Result<Self, CutError> {
        let needed = Self::words_needed(o);
        let given = memory.len();
        let Some(memory) = memory.get_mut(..needed) else {
            return Err(CutError::Capacity { needed, given });
        };
        let (counts, halves) = memory.split_at_mut(o.surface_count());
        counts.fill(0);
        Ok(Self {
            identity: o.identity(),
            node_count: o.node_count() as u32,
            current: 0,
            len: [0, 0],
            counts,
            halves,
        })
    }

    /// Was this cut made for `o`?
    pub fn is_for(&self, o: &Octree<'_>) -> bool {
        self.identity == o.identity()
            && self.node_count as usize == o.node_count()
            && self.counts.len() == o.surface_count()
    }

    /// Forgets the current and previous cuts: the next selection enters every node it takes.
    pub fn reset(&mut self) {
        self.len = [0, 0];
        self.counts.fill(0);
    }

    fn half(&self, which: usize) -> &[u32] {
        let n = self.node_count as usize;
        let start = which * n;
        self.halves
            .get(start..start + self.len[which] as usize)
            .unwrap_or(&[])
    }

    /// The node ids of the current cut, ascending.
    pub fn selected(&self) -> &[u32] {
        self.half(self.current)
    }

    /// The node ids of the previous cut, ascending.
    pub fn previous(&self) -> &[u32] {
        self.half(1 - self.current)
    }

    /// Nodes of the current cut that were not in the previous one, ascending.
    pub fn entered(&self) -> Difference<'_> {
        Difference {
            a: self.selected(),
            b: self.previous(),
        }
    }

    /// Nodes of the previous cut that are not in the current one, ascending.
    pub fn left(&self) -> Difference<'_> {
        Difference {
            a: self.previous(),
            b: self.selected(),
        }
    }

    /// Chooses this camera's nodes: from the root, a node whose box is outside the frustum
    /// is skipped with its subtree; a node is taken when its error projects to at most
    /// `tolerance_px` pixels (`error × pixels_per_radian / distance`, the distance from the
    /// eye to its box) or it is at level 0; otherwise its children are looked at. The
    /// previous cut is kept for [`entered`](Self::entered) and [`left`](Self::left).
    /// Allocates nothing; work is proportional to the nodes visited.
    ///
    /// The tolerance is checked as refinement checks it: [`CutError::InvalidParams`] for one
    /// that is not a finite number above 0, and the cut is left as it was.
    pub fn select(
        &mut self,
        o: &Octree<'_>,
        view: &View,
        tolerance_px: f32,
    ) -> Result<SelectStats, CutError> {
        if !self.is_for(o) {
            return Err(CutError::WrongOctree);
        }
        // The hierarchy's screen-space test: error / distance against the tolerance in
        // radians; no pixel scale means nothing needs refining.
        let test = ScreenTest::of_tolerance(view, tolerance_px)?;
        let n = self.node_count as usize;
        let next_half = 1 - self.current;
        let (first, second) = self.halves.split_at_mut(n);
        let (prev, next) = if next_half == 1 {
            (&first[..], second)
        } else {
            (&second[..], first)
        };
        let prev = prev.get(..self.len[self.current] as usize).unwrap_or(&[]);
        let nodes = o.nodes();
        self.counts.fill(0);
        let mut stats = SelectStats::default();
        // Queue `next[read..tail]`; the cut `next[..write]` with `write <= read`.
        let (mut read, mut tail, mut write) = (0usize, 0usize, 0usize);
        if let Some(slot) = next.first_mut() {
            *slot = 0;
            tail = 1;
        }
        while read < tail {
            let id = next[read];
            read += 1;
            let Some(node) = nodes.get(id as usize) else {
                continue;
            };
            stats.visited += 1;
            if !box_visible(view, node) {
                stats.culled += 1;
                continue;
            }
            let take = node.level == 0 || test.error_fits(node.error, box_distance(view.eye, node));
            if take {
                next[write] = id;
                write += 1;
                for r in o.ranges_of(node) {
                    if let Some(c) = self.counts.get_mut(r.surface as usize) {
                        *c = c.saturating_add(r.index_count);
                    }
                }
                continue;
            }
            // Validation makes every node some node's child exactly once, so the queue
            // never holds more than `node_count` entries.
            for child in node.children() {
                if let Some(slot) = next.get_mut(tail) {
                    *slot = child;
                    tail += 1;
                }
            }
        }
        let cut = &next[..write];
        let common = Difference { a: cut, b: prev }.common();
        stats.selected = write as u32;
        stats.entered = (cut.len() - common) as u32;
        stats.left = (prev.len() - common) as u32;
        stats.triangles = self.counts.iter().map(|&c| c / 3).sum();
        self.current = next_half;
        self.len[next_half] = write as u32;
        Ok(stats)
    }

    /// Indices surface `surface`'s list needs for the current cut.
    pub fn index_count(&self, surface: usize) -> usize {
        self.counts.get(surface).map_or(0, |&c| c as usize)
    }

    /// Indices of all surfaces together.
    pub fn total_index_count(&self) -> usize {
        self.counts.iter().map(|&c| c as usize).sum()
    }

    /// Writes each surface's indices (the ranges of the selected nodes, in node order) to
    /// the start of `out[surface]` and its count to `written[surface]`. Returns the total.
    /// The indices point into the octree's vertex buffer.
    pub fn emit_indices(
        &self,
        o: &Octree<'_>,
        out: &mut [&mut [u32]],
        written: &mut [u32],
    ) -> Result<usize, CutError> {
        if !self.is_for(o) {
            return Err(CutError::WrongOctree);
        }
        let ns = o.surface_count();
        check_lists(out, written, ns, |s| self.index_count(s))?;
        written[..ns].fill(0);
        let mut total = 0;
        self.for_each_range(o, |s, src| {
            let at = written[s] as usize;
            if let Some(dst) = out[s].get_mut(at..at + src.len()) {
                dst.copy_from_slice(src);
                written[s] += src.len() as u32;
                total += src.len();
            }
        });
        Ok(total)
    }

    /// Writes every surface's indices back to back into `out`; `offsets` (surfaces + 1
    /// entries) receives the ranges: surface `s` is `out[offsets[s]..offsets[s + 1]]`.
    /// Returns the total number of indices.
    pub fn emit_indices_packed(
        &self,
        o: &Octree<'_>,
        out: &mut [u32],
        offsets: &mut [u32],
    ) -> Result<usize, CutError> {
        if !self.is_for(o) {
            return Err(CutError::WrongOctree);
        }
        let ns = o.surface_count();
        let total = start_packed(out.len(), offsets, ns, |s| self.index_count(s))?;
        self.for_each_range(o, |s, src| {
            let at = offsets[s + 1] as usize;
            if let Some(dst) = out.get_mut(at..at + src.len()) {
                dst.copy_from_slice(src);
                offsets[s + 1] += src.len() as u32;
            }
        });
        Ok(total)
    }

    /// Calls `sink(surface, indices)` for every range of every selected node, in node order.
    #[inline]
    fn for_each_range(&self, o: &Octree<'_>, mut sink: impl FnMut(usize, &[u32])) {
        let nodes = o.nodes();
        for &id in self.selected() {
            let Some(node) = nodes.get(id as usize) else {
                continue;
            };
            for r in o.ranges_of(node) {
                sink(r.surface as usize, o.range_indices(r));
            }
        }
    }
}

/// The ids of one ascending list that are not in another ([`OctreeCut::entered`],
/// [`OctreeCut::left`]).
#[derive(Clone, Debug)]
pub struct Difference<'c> {
    a: &'c [u32],
    b: &'c [u32],
}

impl Difference<'_> {
    /// How many ids the two lists share.
    fn common(mut self) -> usize {
        let mut n = 0;
        while let (Some(&x), Some(&y)) = (self.a.first(), self.b.first()) {
            if x <= y {
                self.a = &self.a[1..];
            }
            if y <= x {
                self.b = &self.b[1..];
            }
            n += usize::from(x == y);
        }
        n
    }
}

impl Iterator for Difference<'_> {
    type Item = u32;

    fn next(&mut self) -> Option<u32> {
        loop {
            let (&x, rest) = self.a.split_first()?;
            while let Some((&y, b_rest)) = self.b.split_first() {
                if y >= x {
                    break;
                }
                self.b = b_rest;
            }
            self.a = rest;
            if self.b.first() != Some(&x) {
                return Some(x);
            }
        }
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        (0, Some(self.a.len()))
    }
}

#[cfg(test)]
mod tests {
    use super::Difference;

    fn diff(a: &[u32], b: &[u32]) -> ([u32; 8], usize, usize) {
        let mut out = [u32::MAX; 8];
        let mut n = 0;
        for (slot, x) in out.iter_mut().zip(Difference { a, b }) {
            *slot = x;
            n += 1;
        }
        (out, n, Difference { a, b }.common())
    }

    /// `a`, `b`, `a - b`, `|a ∩ b|`.
    type Case = (&'static [u32], &'static [u32], &'static [u32], usize);

    #[test]
    fn differences_of_ascending_lists() {
        let cases: [Case; 7] = [
            (&[], &[], &[], 0),
            (&[1, 2, 3], &[], &[1, 2, 3], 0),
            (&[], &[1, 2], &[], 0),
            (&[1, 3, 5, 7], &[3, 7], &[1, 5], 2),
            (&[2, 4], &[1, 2, 3, 4, 5], &[], 2),
            (&[1, 4, 9, 10], &[0, 5, 9, 11], &[1, 4, 10], 1),
            (&[5, 6, 7], &[1, 2, 3], &[5, 6, 7], 0),
        ];
        for (a, b, expected, common) in cases {
            let (out, n, c) = diff(a, b);
            assert_eq!(&out[..n], expected, "{a:?} - {b:?}");
            assert_eq!(c, common, "{a:?} & {b:?}");
        }
    }
}
