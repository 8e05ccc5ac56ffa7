//! What the settling of the error bounds reads of a pass's applied collapses, taken from the
//! work as each is applied ([`Work::take_over`], while what it reads is in cache): the new
//! node, the positions of its two children, and the corners of its triangles and of the two
//! that died. The collapses of a pass have disjoint stars, which no later collapse of the
//! pass changes, so this is what the settling would read at the end of the pass, and it can
//! run while the pass goes on.

use super::work::Work;
use super::{Collapse, NONE};

/// A triangle as the settling reads it: its id and its corners' positions.
pub(super) type Corners = (u32, [u32; 3]);

/// One collapse as the settling reads it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Entry {
    /// The new node.
    pub(super) node: u32,
    /// Its error from its children.
    pub(super) error: f32,
    /// The positions of the new node (the kept child's) and of the removed child.
    pub(super) at: u32,
    pub(super) was: u32,
    /// Where its triangles start in [`Handover::tris`]: the new node's star (those from the
    /// kept child first), then the one or two that died.
    start: u32,
    /// How many of the star's came from the kept child.
    kept: u32,
    /// How many the star has.
    star: u32,
    /// How many died.
    dying: u32,
}

/// A run of a pass's applied collapses, in order, as the settling reads them.
#[derive(Debug, Default)]
pub(super) struct Handover {
    entries: Vec<Entry>,
    tris: Vec<Corners>,
}

impl Handover {
    /// The collapses.
    pub(super) fn entries(&self) -> &[Entry] {
        &self.entries
    }

    /// The new node's triangles.
    pub(super) fn star(&self, e: &Entry) -> &[Corners] {
        let s = e.start as usize;
        &self.tris[s..s + e.star as usize]
    }

    /// The new node's triangles from the kept child.
    pub(super) fn kept(&self, e: &Entry) -> &[Corners] {
        &self.star(e)[..e.kept as usize]
    }

    /// The new node's triangles from the removed child (it gave them).
    pub(super) fn given(&self, e: &Entry) -> &[Corners] {
        &self.star(e)[e.kept as usize..]
    }

    /// The triangles that died, with their corners as they were.
    pub(super) fn dying(&self, e: &Entry) -> &[Corners] {
        let s = (e.start + e.star) as usize;
        &self.tris[s..s + e.dying as usize]
    }
}

impl Work<'_> {
    /// Adds the collapse `c` just applied, which made node `s` with `kept` triangles from
    /// its kept child (listed first), to the collapses taken for the settling.
    pub(super) fn take_over(&mut self, c: Collapse, s: u32, kept: usize) {
        let Work {
            taken,
            tris,
            node_pos,
            faces_of,
            nodes,
            ..
        } = self;
        let corners = |f: u32| (f, tris[f as usize].c.map(|v| node_pos[v as usize]));
        let star = faces_of.of(s);
        let start = taken.tris.len() as u32;
        taken.tris.extend(star.iter().map(|&f| corners(f)));
        let dying = [c.fl, c.fr].into_iter().filter(|&f| f != NONE);
        taken.tris.extend(dying.map(corners));
        taken.entries.push(Entry {
            node: s,
            error: nodes[s as usize].error,
            at: node_pos[c.t as usize],
            was: node_pos[c.u as usize],
            start,
            kept: kept as u32,
            star: star.len() as u32,
            dying: taken.tris.len() as u32 - start - star.len() as u32,
        });
    }

    /// The collapses taken since the last call, for the settling.
    pub(super) fn handover(&mut self) -> Handover {
        std::mem::take(&mut self.taken)
    }
}
